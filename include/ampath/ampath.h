/*
 * ampath/ampath.h — the front page of the library, and the umbrella header
 * that includes every public module.
 *
 * What it does: print paths for fused-filament printers. Volumetric paths
 * that cover a trivariate or a mesh with curves in 3-D ([P1]), continuous
 * planar strokes for layered printing ([P2]), a gouge-free print order for a
 * conical head, deposition radii, support, G-code, previews, and the printer
 * protocol engine of the bridge. The papers and the interface reference are
 * cited as [P1 §x], [P2 §x] and docs/interfaces.md §N (docs/ARCHITECTURE.md).
 *
 * The pipeline, and the header serving each stage:
 *   model        spline.h (.spl, built-in trivariates), mesh.h (.stl, built-in meshes), bvh.h
 *   cover        cover.h (trivariate, [P1 §4.1]), field.h (mesh + direction field, [P1 §4.2])
 *   slice        slice.h, polygon.h, complex2.h, euler.h, contpath.h (continuous strokes, [P2])
 *   paths        paths.h (the .amp format, docs/interfaces.md §3)
 *   order        head.h (the head cone), order.h (fragments, Algorithm 2, [P1 §5.1])
 *   radius       mdr.h ([P1 §5.2])
 *   support      support.h ([P1 §5.3])
 *   check        check.h (the independent checkers: gouge, stroke, coverage, held paths)
 *   output       printer.h (profiles), gcode.h (docs/interfaces.md §5), preview.h (SVG/PNG)
 *   printer link proto.h (Marlin/Klipper protocol engine, no I/O)
 *   support code status.h (errors), alloc.h (allocator), io.h (sinks, files), vec.h, version.h
 *
 * Conventions, for every header:
 * - Errors: a fallible function returns amp_status (AMP_OK = 0) and fills an
 *   optional caller-owned amp_error with a one-line reason (amp_fail). The
 *   library never prints, never exits and has no global mutable state.
 * - Memory and ownership: every object remembers the amp_allocator it was
 *   made with (NULL: malloc) and frees through it; an object passed by const
 *   pointer is read only and stays the caller's; an output object is
 *   initialised by the callee and freed by the caller with the matching
 *   *_free(). Each function's comment states what it allocates.
 * - Units: millimetres, seconds, radians (the tool speaks degrees); +z is the
 *   build direction, z = 0 the plate (docs/interfaces.md §2).
 * - Thread-safety: functions are reentrant; read-only objects may be shared
 *   between threads; an object being written belongs to one thread. Some
 *   stages use OpenMP inside a call when built with it.
 * - Progress: long calls take an optional progress callback in their options.
 * - Options structs are filled by *_opts_default() first, then changed.
 *
 * Versions: version.h. There is no ABI promise before 1.0: structs may grow
 * and functions may change between 0.x releases; rebuild against the headers
 * you link with. The shared library exports exactly the functions declared
 * in these headers (tools/exports.sh, tests/test_exports.c).
 */
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
