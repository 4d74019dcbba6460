/*
 * A voxel map of a closed mesh's solid (amp_bvh_voxels_build of include/ampath/bvh.h): the inside test of
 * amp_bvh_inside() without a ray wherever the surface is not near. A closed mesh's winding number is an
 * integer that changes only across the surface, so it is constant over a cell no triangle reaches, and over
 * any group of such cells joined by faces: one ray per group answers for all of them.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ampath/bvh.h"
#include "bvh_internal.h"

enum { VOX_OUT = 0, VOX_IN = 1, VOX_NEAR = 2, VOX_UNKNOWN = 3 };

struct amp_bvh_voxels {
    const amp_allocator *alloc;
    amp_vec3 lo;        /* corner of cell (0, 0, 0) */
    double inv;         /* 1 / cell side */
    size_t n[3];        /* cells along x, y, z */
    unsigned char *c;   /* VOX_* per cell, x fastest */
};

/* Coordinate k (0: x, 1: y, 2: z) of p. */
static double axis(amp_vec3 p, int k) { return k == 0 ? p.x : k == 1 ? p.y : p.z; }

/* The cell range [*i0, *i1] along axis k that the interval [a, b] reaches, widened by a millionth of a cell
 * so that a triangle on a cell's face marks the cells on both sides. */
static void cell_range(const amp_bvh_voxels *v, int k, double a, double b, size_t *i0, size_t *i1)
{
    const double lo = axis(v->lo, k);
    double f0 = floor((a - lo) * v->inv - 1e-6), f1 = floor((b - lo) * v->inv + 1e-6);
    *i0 = f0 < 0 ? 0 : (size_t)f0;
    *i1 = f1 < 0 ? 0 : f1 > (double)(v->n[k] - 1) ? v->n[k] - 1 : (size_t)f1;
}

/* Every cell the box of a triangle reaches is near the surface. */
static void mark_surface(amp_bvh_voxels *v, const amp_bvh *b)
{
    size_t t, x, y, z, r[3][2];
    int k;
    for (t = 0; t < b->ntris; t++) {
        const amp_vec3 *p = b->tris[t].p;
        for (k = 0; k < 3; k++) {
            double a = axis(p[0], k), b1 = axis(p[1], k), c = axis(p[2], k);
            cell_range(v, k, fmin(a, fmin(b1, c)), fmax(a, fmax(b1, c)), &r[k][0], &r[k][1]);
        }
        for (z = r[2][0]; z <= r[2][1]; z++)
            for (y = r[1][0]; y <= r[1][1]; y++)
                for (x = r[0][0]; x <= r[0][1]; x++)
                    v->c[(z * v->n[1] + y) * v->n[0] + x] = VOX_NEAR;
    }
}

/* The group of unknown cells joined by faces to cell @p s takes the side at its centre (queue: room for every
 * cell). */
static void fill_group(amp_bvh_voxels *v, const amp_bvh *b, size_t s, uint32_t *queue)
{
    const size_t nx = v->n[0], ny = v->n[1], nz = v->n[2];
    size_t head = 0, tail = 0, x = s % nx, y = s / nx % ny, z = s / nx / ny;
    double h = 1.0 / v->inv;
    unsigned char side = (unsigned char)(amp_bvh_inside(b, amp_v3(v->lo.x + (x + 0.5) * h, v->lo.y + (y + 0.5) * h,
                                                                   v->lo.z + (z + 0.5) * h)) ? VOX_IN : VOX_OUT);
    v->c[s] = side;
    queue[tail++] = (uint32_t)s;
    while (head < tail) {
        size_t i = queue[head++], nb[6], k, m = 0;
        x = i % nx;
        y = i / nx % ny;
        z = i / nx / ny;
        if (x > 0) nb[m++] = i - 1;
        if (x + 1 < nx) nb[m++] = i + 1;
        if (y > 0) nb[m++] = i - nx;
        if (y + 1 < ny) nb[m++] = i + nx;
        if (z > 0) nb[m++] = i - nx * ny;
        if (z + 1 < nz) nb[m++] = i + nx * ny;
        for (k = 0; k < m; k++)
            if (v->c[nb[k]] == VOX_UNKNOWN) {
                v->c[nb[k]] = side;
                queue[tail++] = (uint32_t)nb[k];
            }
    }
}

amp_status amp_bvh_voxels_build(const amp_bvh *b, size_t max_cells, amp_bvh_voxels **out, amp_error *err)
{
    amp_bvh_voxels *v;
    size_t i, cells;
    uint32_t *queue;
    double ext[3], h;
    int k;
    if (!b || !out || max_cells < 1 || max_cells > UINT32_MAX)
        return amp_fail(err, AMP_ERR_ARG, 0, "voxels: NULL BVH or output, or a cell count outside 1 .. 2^32 - 1");
    *out = NULL;
    if (!b->closed)
        return AMP_OK;
    ext[0] = b->bbox.max.x - b->bbox.min.x;
    ext[1] = b->bbox.max.y - b->bbox.min.y;
    ext[2] = b->bbox.max.z - b->bbox.min.z;
    /* cubes of side h, the box split into about max_cells of them (a flat box: by its area) */
    h = cbrt(fmax(ext[0], 1e-9) * fmax(ext[1], 1e-9) * fmax(ext[2], 1e-9) / (double)max_cells);
    for (k = 0; k < 3; k++)
        h = fmax(h, ext[k] / 1e6);
    for (;;) {
        double n = 1;
        for (k = 0; k < 3; k++)
            n *= floor(ext[k] / h) + 1;
        if (n <= (double)max_cells)
            break;
        h *= 1.05;
    }
    if (!(v = amp_calloc(b->alloc, 1, sizeof *v)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the voxel map");
    v->alloc = b->alloc;
    v->lo = b->bbox.min;
    v->inv = 1.0 / h;
    for (k = 0, cells = 1; k < 3; k++)
        cells *= v->n[k] = (size_t)floor(ext[k] / h) + 1;
    v->c = amp_alloc(b->alloc, cells);
    queue = amp_alloc(b->alloc, cells * sizeof *queue);
    if (!v->c || !queue) {
        amp_free(b->alloc, queue);
        amp_bvh_voxels_free(v);
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the voxel map");
    }
    memset(v->c, VOX_UNKNOWN, cells);
    mark_surface(v, b);
    for (i = 0; i < cells; i++)
        if (v->c[i] == VOX_UNKNOWN)
            fill_group(v, b, i, queue);
    amp_free(b->alloc, queue);
    *out = v;
    return AMP_OK;
}

int amp_bvh_voxels_side(const amp_bvh_voxels *v, amp_vec3 p)
{
    double f[3];
    size_t i[3];
    int k;
    f[0] = (p.x - v->lo.x) * v->inv;
    f[1] = (p.y - v->lo.y) * v->inv;
    f[2] = (p.z - v->lo.z) * v->inv;
    for (k = 0; k < 3; k++) {
        if (!(f[k] >= 0) || f[k] >= (double)v->n[k])
            return f[k] == f[k] ? 0 : -1; /* outside the box: outside the solid; NaN: ask the BVH */
        i[k] = (size_t)f[k];
    }
    switch (v->c[(i[2] * v->n[1] + i[1]) * v->n[0] + i[0]]) {
    case VOX_IN: return 1;
    case VOX_OUT: return 0;
    default: return -1;
    }
}

void amp_bvh_voxels_free(amp_bvh_voxels *v)
{
    if (!v)
        return;
    amp_free(v->alloc, v->c);
    amp_free(v->alloc, v);
}
