/* ampath/ampath.h — umbrella header: includes every public module. */
#ifndef AMPATH_AMPATH_H
#define AMPATH_AMPATH_H

#include "alloc.h"
#include "bvh.h"
#include "check.h"
#include "complex2.h"
#include "contpath.h"
#include "cover.h"
#include "euler.h"
#include "field.h"
#include "gcode.h"
#include "head.h"
#include "io.h"
#include "mdr.h"
#include "mesh.h"
#include "order.h"
#include "paths.h"
#include "polygon.h"
#include "preview.h"
#include "printer.h"
#include "proto.h"
#include "slice.h"
#include "spline.h"
#include "status.h"
#include "support.h"
#include "vec.h"
#include "version.h"

#endif
