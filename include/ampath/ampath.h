/* ampath/ampath.h — umbrella header: includes every public module. */
#ifndef AMPATH_AMPATH_H
#define AMPATH_AMPATH_H

#include "alloc.h"
#include "io.h"
#include "mesh.h"
#include "bvh.h"
#include "field.h"
#include "order.h"
#include "gouge.h"
#include "mdr.h"
#include "support.h"
#include "paths.h"
#include "status.h"
#include "vec.h"
#include "version.h"

#endif
