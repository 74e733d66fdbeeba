/* The settings tab (filled in by its own change). */
'use strict';
