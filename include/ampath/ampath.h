/* ampath/ampath.h — umbrella header: includes every public module. */
#ifndef AMPATH_AMPATH_H
#define AMPATH_AMPATH_H

#include "alloc.h"
#include "bvh.h"
#include "complex2.h"
#include "contpath.h"
#include "cover.h"
#include "euler.h"
#include "field.h"
#include "gcode.h"
#include "io.h"
#include "mesh.h"
#include "paths.h"
#include "polygon.h"
#include "proto.h"
#include "slice.h"
#include "spline.h"
#include "status.h"
#include "vec.h"
#include "version.h"

#endif
