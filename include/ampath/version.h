/* ampath/version.h — the one place the version lives (the Makefile reads it). */
#ifndef AMPATH_VERSION_H
#define AMPATH_VERSION_H

#define AMP_VERSION_MAJOR 0
#define AMP_VERSION_MINOR 1
#define AMP_VERSION_PATCH 0
#define AMP_VERSION_STRING "0.1.0"

#endif
