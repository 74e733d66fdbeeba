/* The motion tab (filled in by its own change). */
'use strict';
