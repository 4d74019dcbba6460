/* ampath/ampath.h — umbrella header: includes every public module. */
#ifndef AMPATH_AMPATH_H
#define AMPATH_AMPATH_H

#include "alloc.h"
#include "io.h"
#include "mesh.h"
#include "bvh.h"
#include "paths.h"
#include "polygon.h"
#include "complex2.h"
#include "euler.h"
#include "contpath.h"
#include "slice.h"
#include "status.h"
#include "vec.h"
#include "version.h"

#endif
