/* ampath/ampath.h — umbrella header: includes every public module. */
#ifndef AMPATH_AMPATH_H
#define AMPATH_AMPATH_H

#include "alloc.h"
#include "gcode.h"
#include "io.h"
#include "mesh.h"
#include "paths.h"
#include "proto.h"
#include "status.h"
#include "vec.h"
#include "version.h"

#endif
