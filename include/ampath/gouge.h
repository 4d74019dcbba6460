/*
 * ampath/gouge.h — independent gouge checker for an ordered set of paths.
 *
 * Paths are printed in order, each from its first to its last vertex. The
 * check fails when a point printed earlier lies inside the head cone
 * (amp_head, SPEC §2) while a later point is printed: for an earlier point q
 * and a later point p, (q.z - p.z - z_offs) - cot(theta) |q.xy - p.xy| > tol.
 * Earlier points include the earlier part of the same path and of the same
 * segment (a steep descent gouges itself).
 *
 * This code shares nothing with the orderer (order.h): it maximises the
 * clearance numerically (golden-section search over the later segment with an
 * exact inner maximum over the earlier one), so it can check it.
 * Thread-safe; the pairwise method uses OpenMP.
 */
#ifndef AMPATH_GOUGE_H
#define AMPATH_GOUGE_H

#include <stddef.h>

#include "order.h"
#include "paths.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum amp_gouge_method {
    AMP_GOUGE_AUTO = 0,     /**< pairwise below 2000 segments, grid above */
    AMP_GOUGE_PAIRWISE = 1, /**< every pair of segments: O(S^2) */
    AMP_GOUGE_GRID = 2      /**< earlier segments in a column grid with a max-height pyramid, visited in print order */
} amp_gouge_method;

/** The first violation: the earliest later segment, and for it the earliest earlier segment. */
typedef struct amp_gouge_violation {
    size_t earlier_path, earlier_seg; /**< segment k joins vertices k and k+1 of the path (0 for a one-vertex path) */
    size_t later_path, later_seg;
    amp_vec3 earlier_point;           /**< the printed point inside the head ... */
    amp_vec3 later_point;             /**< ... while this point is printed */
    double depth;                     /**< how far inside the cone, mm (> tol) */
} amp_gouge_violation;

/** Default tolerance (mm): tiny contacts from rounding in the .amp text are not gouges. */
#define AMP_GOUGE_TOL 1e-6

/**
 * Check @p ps for gouging with head @p h. Returns AMP_OK when no violation
 * exists, AMP_ERR_CHECK when one does (then @p v, if not NULL, holds the first
 * one and err->msg says where), AMP_ERR_RANGE for a bad head or tolerance,
 * AMP_ERR_NOMEM. Both methods report the same first violation.
 */
amp_status amp_gouge_check(const amp_pathset *ps, const amp_head *h, amp_gouge_method m, double tol,
                           amp_gouge_violation *v, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
