/*
 * ampath/support.h — support structure (paper §5.3).
 *
 * Vertical rays on an xy grid (spacing = density) are cast through the model;
 * every stretch of a ray that lies outside the solid but below it (from the
 * plate z = 0, or from the top of a lower part of the solid, up to the
 * underside above) is support volume. That volume is filled on the same grid
 * with straight support paths (role support), one layer every layer_height
 * mm, rows along x on even layers and along y on odd ones. Each support path
 * is then placed just before the first object path (in the given print order)
 * whose head-cone sweep lies above it (Def. 5.1: the support is below that
 * path), so that the support under a path is printed before the path, in
 * stages. Support paths with no object path above them are printed last.
 * The reverse constraint (an object path printed later that lies below a
 * support fragment, e.g. in a thin overhang gap or under a steep underside)
 * cannot be met by any placement: such fragments are left out (the support
 * path is split around them), counted in amp_support_stats.conflicts and
 * .trimmed, so the result passes the gouge check.
 * Thread-safe; the model's BVH is only read.
 */
#ifndef AMPATH_SUPPORT_H
#define AMPATH_SUPPORT_H

#include <stddef.h>

#include "bvh.h"
#include "order.h"
#include "paths.h"
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct amp_support_opts {
    amp_head head;       /**< print head (for the ordering) */
    double spacing;      /**< grid spacing of rays and support rows, mm (default 2) */
    double layer_height; /**< vertical distance of support layers, mm (default 0.4) */
    double radius;       /**< deposition radius of support paths, mm (default 0.2) */
    double min_gap;      /**< ignore air gaps lower than this, mm (default 1) */
} amp_support_opts;

void amp_support_opts_default(amp_support_opts *o);

typedef struct amp_support_stats {
    size_t rays;          /**< vertical rays cast */
    size_t columns;       /**< ray stretches that need support */
    size_t paths;         /**< support paths written (after splitting around conflicts) */
    double length;        /**< length of the support rows made, mm (before trimming) */
    size_t unplaced;      /**< support paths with no object path above (printed last) */
    size_t conflicts;     /**< support rows that also lay above an object path printed after them */
    double trimmed;       /**< length left out for those conflicts, mm */
} amp_support_stats;

/**
 * Add support for @p model (BVH of the closed model mesh) under the paths of
 * @p in and append everything to @p out in print order (object paths keep
 * their order; support paths are interleaved as described above; support
 * paths already in @p in are kept in place). @p st may be NULL.
 * Errors: AMP_ERR_RANGE (bad options or head), AMP_ERR_LIMIT, AMP_ERR_NOMEM.
 */
amp_status amp_support(const amp_pathset *in, const amp_bvh *model, const amp_support_opts *o, amp_pathset *out,
                       amp_support_stats *st, amp_error *err);

#ifdef __cplusplus
}
#endif
#endif
