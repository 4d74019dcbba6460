/*
 * Curves through the gaps of a field's covering (field_internal.h).
 *
 * The adaptive lattice (lib/field.c) checks its covering radius on a 5 x 5 grid per cell at samples along
 * the curves: a sampled bound. Features finer than those samples (a screw's threads, a recycling symbol's
 * strokes, a bed's ribs) can still leave solid farther than the radius from every printed curve, and
 * `ampath check` then measures a gap above it. Here the solid is sampled uniformly, each sample is tested
 * against the paths (is a segment within the covering radius?), and the field's own curve through each
 * sample that fails is added: the paths stay curves of the field ([P1 §4.2]), only more of them. The test
 * is this file's own (a hash of points along the paths), not the checker's: `check` stays independent.
 */
#include <math.h>
#include <string.h>

#include "bvh_internal.h"
#include "field_internal.h"

#define GAP_ROUNDS 6          /* sample, add curves; a last sampling only counts what is left */
#define GAP_SAMPLES 100000    /* samples of the solid in the first round (five times the checker's default) */
#define GAP_SAMPLES_MAX 800000 /* each round that still finds gaps samples twice as many, up to this */
#define GAP_SEED 0x6A9C0F3Bull
#define GAP_POINTS_MAX 4096   /* gaps looked at per round */
#define GAP_SEEDS_MAX 65536   /* curve samples tried as Newton's starting point */
#define VOXELS_MAX (1u << 21) /* cells of the solid's voxel map (a byte each) */

/* ------------------------------------------- which samples are near a path */

/*
 * Points along every path segment at most `target` apart, hashed by a cell of 1.5 target, each naming its
 * segment. A sample within `target` of a segment is within 1.5 target of one of its points, so the 27 cells
 * around the sample hold that segment; the distance to each segment met there is exact.
 */
typedef struct near_entry {
    size_t seg;  /* index in ps->verts of the segment's first vertex */
    size_t next; /* next entry of the bucket + 1 (0: last) */
} near_entry;

typedef struct near_index {
    const amp_pathset *ps;
    double target, cell;
    size_t *bucket, nbucket; /* first entry + 1 (0: empty); nbucket a power of two */
    near_entry *e;
    size_t n, cap;
    size_t paths; /* paths indexed so far */
} near_index;

static size_t bucket_of(const near_index *x, long long cx, long long cy, long long cz)
{
    unsigned long long h = (unsigned long long)cx * 0x9E3779B97F4A7C15ULL ^
                           (unsigned long long)cy * 0xC2B2AE3D27D4EB4FULL ^
                           (unsigned long long)cz * 0x165667B19E3779F9ULL;
    return (size_t)(h >> 20) & (x->nbucket - 1);
}

static long long cell_coord(const near_index *x, double v) { return (long long)floor(v / x->cell); }

/* Index the paths added since the last call. */
static amp_status near_add(near_index *x, const amp_allocator *a, amp_error *err)
{
    const amp_pathset *ps = x->ps;
    for (; x->paths < ps->npaths; x->paths++) {
        size_t first = (size_t)(amp_pathset_path_verts(ps, x->paths) - ps->verts), k;
        for (k = 0; k + 1 < ps->paths[x->paths].n; k++) {
            amp_vec3 p0 = ps->verts[first + k].p, p1 = ps->verts[first + k + 1].p;
            size_t m = (size_t)ceil(amp_v3_dist(p0, p1) / x->target), j;
            for (j = 0; j <= m; j++) {
                amp_vec3 p = m ? amp_v3_lerp(p0, p1, (double)j / (double)m) : p0;
                size_t b = bucket_of(x, cell_coord(x, p.x), cell_coord(x, p.y), cell_coord(x, p.z));
                void *mem = x->e;
                if (x->bucket[b] && x->e[x->bucket[b] - 1].seg == first + k)
                    continue; /* the segment's previous point fell in the same bucket */
                if (amp_grow(a, &mem, &x->cap, x->n + 1, sizeof *x->e) != AMP_OK)
                    return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
                x->e = mem;
                x->e[x->n].seg = first + k;
                x->e[x->n].next = x->bucket[b];
                x->bucket[b] = ++x->n;
            }
        }
    }
    return AMP_OK;
}

static amp_status near_init(near_index *x, const amp_pathset *ps, double target, const amp_allocator *a,
                            amp_error *err)
{
    double len = 0.0;
    size_t i, want;
    memset(x, 0, sizeof *x);
    x->ps = ps;
    x->target = target;
    x->cell = 1.5 * target;
    for (i = 0; i < ps->npaths; i++)
        len += amp_path_length(ps, i);
    want = (size_t)(len / target) + (size_t)ps->nverts;
    for (x->nbucket = 4096; x->nbucket < want && x->nbucket < ((size_t)1 << 26); x->nbucket *= 2)
        ;
    if (!(x->bucket = amp_calloc(a, x->nbucket, sizeof *x->bucket)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
    return near_add(x, a, err);
}

static void near_free(near_index *x, const amp_allocator *a)
{
    amp_free(a, x->bucket);
    amp_free(a, x->e);
}

/* Is some path segment within target of @p p? */
static int near_material(const near_index *x, amp_vec3 p)
{
    long long cx = cell_coord(x, p.x), cy = cell_coord(x, p.y), cz = cell_coord(x, p.z);
    double t2 = x->target * x->target;
    int c;
    /* the sample's own cell first (c = 13 there, then skipped): it holds the nearest segment most often */
    for (c = -1; c < 27; c++)
        if (c != 13) {
            long long dx = c < 0 ? 0 : c % 3 - 1, dy = c < 0 ? 0 : c / 3 % 3 - 1, dz = c < 0 ? 0 : c / 9 - 1;
            size_t id = x->bucket[bucket_of(x, cx + dx, cy + dy, cz + dz)];
            for (; id; id = x->e[id - 1].next) {
                size_t s = x->e[id - 1].seg;
                if (amp_v3_seg_dist2(p, x->ps->verts[s].p, x->ps->verts[s + 1].p, NULL) <= t2)
                    return 1;
            }
        }
    return 0;
}

/* -------------------------------------------------- the field, inverted */

/* F at lattice position x = (a, b, c). */
static amp_status field_at(const amp_field *f, const double x[3], amp_vec3 *p, amp_error *err)
{
    double uvw[3];
    amp_field_to_uvw(f, x[0], x[1], x[2], uvw);
    return f->eval(f, uvw, p, err);
}

/* The lattice position of the covering's sample nearest to @p p (every stride-th sample). */
static void nearest_seed(const amp_field_seeds *sd, amp_vec3 p, double x[3])
{
    size_t n = sd->ncur * (sd->ncs + 1), stride = n / GAP_SEEDS_MAX + 1, i, best = 0;
    double bd = HUGE_VAL;
    uint64_t key;
    for (i = 0; i < n; i += stride) {
        double d = amp_v3_dist2(sd->pts[i], p);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    key = sd->key[best / (sd->ncs + 1)];
    x[0] = (double)(key >> 32) / sd->da;
    x[1] = (double)(key & 0xffffffffu) / sd->db;
    x[2] = (double)(best % (sd->ncs + 1)) / (double)sd->ncs;
}

static double clamp01(double v) { return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v); }

/*
 * Solve F(x) = p by Newton's method from the nearest seed, with a forward-difference Jacobian and x kept in
 * the domain. 1 when it lands within @p tol of p; 0 when p is beyond the field's reach (or F is singular).
 */
static int invert(const amp_field *f, const amp_field_seeds *sd, amp_vec3 p, double tol, double x[3])
{
    amp_error err;
    int it, d;
    nearest_seed(sd, p, x);
    for (it = 0; it < 30; it++) {
        amp_vec3 g, col[3], e;
        double det;
        if (field_at(f, x, &g, &err) != AMP_OK)
            return 0;
        e = amp_v3_sub(g, p);
        if (amp_v3_len(e) <= tol)
            return 1;
        for (d = 0; d < 3; d++) {
            double xh[3], h = x[d] < 0.5 ? 1e-7 : -1e-7;
            amp_vec3 gh;
            memcpy(xh, x, sizeof xh);
            xh[d] += h;
            if (field_at(f, xh, &gh, &err) != AMP_OK)
                return 0;
            col[d] = amp_v3_scale(amp_v3_sub(gh, g), 1.0 / h);
        }
        /* J dx = -e by Cramer's rule, J's columns col[0..2] */
        det = amp_v3_dot(col[0], amp_v3_cross(col[1], col[2]));
        if (!(fabs(det) > 1e-300))
            return 0;
        e = amp_v3_scale(e, -1.0);
        x[0] = clamp01(x[0] + amp_v3_dot(e, amp_v3_cross(col[1], col[2])) / det);
        x[1] = clamp01(x[1] + amp_v3_dot(col[0], amp_v3_cross(e, col[2])) / det);
        x[2] = clamp01(x[2] + amp_v3_dot(col[0], amp_v3_cross(col[1], e)) / det);
    }
    return 0;
}

/* ----------------------------------------------------------- the curves */

/* Is @p p within @p lim of path @p i of @p ps? */
static int near_path(const amp_pathset *ps, size_t i, amp_vec3 p, double lim)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, i);
    size_t k;
    for (k = 0; k + 1 < ps->paths[i].n; k++)
        if (amp_v3_seg_dist2(p, v[k].p, v[k + 1].p, NULL) <= lim * lim)
            return 1;
    return 0;
}

/* The field's curve at lattice position (a, b), clipped; its pieces kept as amp_field_fill_gaps() says. */
static amp_status add_curve(const amp_field *f, const amp_bvh *b, const amp_field_opts *o, const double x[3],
                            size_t nc, double r, double min_len, amp_vec3 gap, double target, amp_pvert *curve,
                            amp_pathset *out, amp_error *err)
{
    amp_pathset tmp;
    size_t i;
    amp_status st = amp_field_curve(f, x[0], x[1], nc, r, curve, NULL, err);
    if (st != AMP_OK)
        return st;
    amp_pathset_init(&tmp, out->alloc);
    st = amp_field_clip(b, o, curve, nc + 1, 0.0, &tmp, err);
    for (i = 0; st == AMP_OK && i < tmp.npaths; i++)
        if (amp_path_length(&tmp, i) >= min_len || near_path(&tmp, i, gap, target))
            st = amp_pathset_add(out, AMP_ROLE_OBJECT, amp_pathset_path_verts(&tmp, i), tmp.paths[i].n, err);
    amp_pathset_free(&tmp);
    return st;
}

/* splitmix64: the samples of one round (another generator than the checker's, on seeds of its own). */
static double rnd(unsigned long long *s)
{
    unsigned long long z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return (double)(z >> 11) / 9007199254740992.0;
}

/* What one round works with. */
typedef struct gap_ctx {
    const amp_field *f;
    const amp_bvh *b;
    const amp_field_opts *o;
    const amp_field_seeds *sd;
    size_t nc;
    double target, r, min_len;
    near_index *nx;
    amp_pvert *curve;
    amp_pathset *out;
    size_t *added, tried;
    amp_error *err;
    const amp_bvh_voxels *vox; /* the solid's voxel map (NULL: every sample asks the BVH) */
    double *cum;               /* running sum of the BVH's triangle areas (surface_point) */
} gap_ctx;

/* The curve through gap @p p, and the index told of it; nothing when the field does not reach p. */
static amp_status close_gap(gap_ctx *c, amp_vec3 p)
{
    double x[3];
    amp_status st;
    if (c->tried++ >= GAP_POINTS_MAX || !invert(c->f, c->sd, p, 1e-3 * c->target, x))
        return AMP_OK;
    (*c->added)++;
    st = add_curve(c->f, c->b, c->o, x, c->nc, c->r, c->min_len, p, c->target, c->curve, c->out, c->err);
    return st == AMP_OK ? near_add(c->nx, c->out->alloc, c->err) : st;
}

/* amp_field_member(), the mesh's side read off the voxel map away from the surface (the same answer: a round
 * samples up to 100 points for each one inside a part that fills little of its box, and each asked the BVH) */
static int member(const gap_ctx *c, amp_vec3 p)
{
    int side = c->vox ? amp_bvh_voxels_side(c->vox, p) : -1;
    if (side == 0)
        return 0;
    if (side == 1 && !c->o->within && c->o->nwithout == 0)
        return 1;
    return amp_field_member(c->b, c->o, p);
}

/* Running sums of the triangle areas, for surface_point. */
static amp_status surface_init(gap_ctx *c, const amp_allocator *a, amp_error *err)
{
    const struct amp_bvh *b = c->b;
    double sum = 0.0;
    size_t i;
    if (!(c->cum = amp_calloc(a, b->ntris + 1, sizeof *c->cum)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
    for (i = 0; i < b->ntris; i++) {
        const amp_vec3 *t = b->tris[i].p;
        sum += 0.5 * amp_v3_len(amp_v3_cross(amp_v3_sub(t[1], t[0]), amp_v3_sub(t[2], t[0])));
        c->cum[i] = sum;
    }
    return AMP_OK;
}

/*
 * A point under the surface: a triangle drawn by area, a uniform point of it, moved inward (the BVH's
 * triangles face out) by up to the target, nearer the surface more often. The gaps the lattice leaves lie
 * next to the surface (inside, a full cell's half diagonal is the target), in features thinner than a cell
 * (a cow's horn, a screw's thread) whose volume uniform samples seldom hit; their surface they share with
 * many such samples (0.90 mm on CGAL's cow at S = 1, found by `check` one seed in 13, before).
 */
static amp_vec3 surface_point(const gap_ctx *c, unsigned long long *seed)
{
    const struct amp_bvh *b = c->b;
    double u = rnd(seed) * c->cum[b->ntris - 1], s = sqrt(rnd(seed)), t = rnd(seed), d = rnd(seed);
    size_t lo = 0, hi = b->ntris - 1;
    const amp_vec3 *tp;
    amp_vec3 n, p;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->cum[mid] < u)
            lo = mid + 1;
        else
            hi = mid;
    }
    tp = b->tris[lo].p;
    p = amp_v3_add(amp_v3_scale(tp[0], 1.0 - s),
                   amp_v3_add(amp_v3_scale(tp[1], s * (1.0 - t)), amp_v3_scale(tp[2], s * t)));
    n = amp_v3_cross(amp_v3_sub(tp[1], tp[0]), amp_v3_sub(tp[2], tp[0]));
    return amp_v3_sub(p, amp_v3_scale(n, d * d * c->target / fmax(amp_v3_len(n), 1e-300)));
}

/* One round: sample the covered part, every other draw uniformly in its box and the others under its surface
 * (surface_point: nearly all kept, so a part that fills little of its box keeps mostly those), and close each
 * sample left far from the paths (the index learns every curve at once, so a gap it closes is not filled
 * twice). *left counts the samples found far (before this round's curves). */
static amp_status gap_round(gap_ctx *c, int add, size_t samples, unsigned long long seed, size_t *left)
{
    amp_box3 box = amp_bvh_bbox(c->b);
    size_t got = 0, tries = 0;
    amp_status st = AMP_OK;
    *left = 0;
    c->tried = 0;
    while (st == AMP_OK && got < samples && tries < 100 * samples) {
        amp_vec3 p = (tries & 1) && c->cum ? surface_point(c, &seed)
                                           : amp_v3(box.min.x + rnd(&seed) * (box.max.x - box.min.x),
                                                    box.min.y + rnd(&seed) * (box.max.y - box.min.y),
                                                    box.min.z + rnd(&seed) * (box.max.z - box.min.z));
        tries++;
        if (!member(c, p))
            continue;
        got++;
        if (near_material(c->nx, p))
            continue;
        (*left)++;
        if (add)
            st = close_gap(c, p);
    }
    return st;
}

amp_status amp_field_fill_gaps(const amp_field *f, const amp_bvh *b, const amp_field_opts *o,
                               const amp_field_seeds *sd, size_t nc, double target, double r, double min_len,
                               amp_pathset *out, size_t *added, size_t *left, amp_error *err)
{
    gap_ctx c;
    near_index nx;
    amp_bvh_voxels *vox = NULL;
    int round;
    amp_status st;
    *added = *left = 0;
    if (sd->ncur == 0 || out->npaths == 0)
        return AMP_OK;
    memset(&c, 0, sizeof c);
    c.f = f;
    c.b = b;
    c.o = o;
    c.sd = sd;
    c.nc = nc;
    c.target = target;
    c.r = r;
    c.min_len = min_len;
    c.nx = &nx;
    c.out = out;
    c.added = added;
    c.err = err;
    if (!(c.curve = amp_calloc(out->alloc, nc + 1, sizeof *c.curve)))
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory for the gap curves");
    st = near_init(&nx, out, target, out->alloc, err);
    if (st == AMP_OK)
        st = amp_bvh_voxels_build(b, VOXELS_MAX, &vox, err);
    if (st == AMP_OK && b->ntris > 0)
        st = surface_init(&c, out->alloc, err);
    c.vox = vox;
    /* gaps are rare where the lattice is fine: a round that finds some samples twice as densely next time,
     * to find the rest of the feature they lie in */
    for (round = 0; st == AMP_OK; round++) {
        size_t before = *added, n = (size_t)GAP_SAMPLES << (round < 4 ? round : 4);
        st = gap_round(&c, round < GAP_ROUNDS, n < GAP_SAMPLES_MAX ? n : GAP_SAMPLES_MAX,
                       GAP_SEED + (unsigned long long)round, left);
        if (*left == 0 || round >= GAP_ROUNDS || *added == before)
            break;
    }
    near_free(&nx, out->alloc);
    amp_bvh_voxels_free(vox);
    amp_free(out->alloc, c.curve);
    amp_free(out->alloc, c.cum);
    return st;
}
