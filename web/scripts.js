/* The scripts tab (filled in by its own change). */
'use strict';
