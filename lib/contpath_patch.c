/* Step 5 (patching) and Figs. 6-8: ring paths between free ends, joins,
 * pseudo edges of thin boundary cells ([P2 §2.2]). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "contpath_internal.h"

int amp_cp_cmp_fend(const void *a, const void *b)
{
    const amp_cp_fend *x = a, *y = b;
    if (x->ring != y->ring)
        return x->ring < y->ring ? -1 : 1;
    return x->pos < y->pos ? -1 : (x->pos > y->pos ? 1 : 0);
}

/* Point at position pos (segment + parameter) of ring r. */
static amp_vec2 ring_point(const amp_polyset *R, size_t r, double pos)
{
    const amp_vec2 *p = amp_polyset_ring(R, r);
    size_t n = R->rings[r].n, s = (size_t)pos % n;
    double u = pos - floor(pos);
    amp_vec2 a = p[s], b = p[(s + 1) % n];
    return amp_v2(a.x + u * (b.x - a.x), a.y + u * (b.y - a.y));
}

/* Length along ring r from position p0 to p1 in ring direction. */
double amp_cp_ring_len(const amp_polyset *R, size_t r, double p0, double p1)
{
    const amp_vec2 *p = amp_polyset_ring(R, r);
    size_t n = R->rings[r].n, s0 = (size_t)p0, s1 = (size_t)p1, s;
    double len = 0;
    amp_vec2 a = ring_point(R, r, p0), b;
    if (s1 == s0 && p1 >= p0) {
        b = ring_point(R, r, p1);
        return hypot(b.x - a.x, b.y - a.y);
    }
    for (s = (s0 + 1) % n;; s = (s + 1) % n) {
        len += hypot(p[s].x - a.x, p[s].y - a.y);
        a = p[s];
        if (s == s1)
            break;
    }
    b = ring_point(R, r, p1);
    return len + hypot(b.x - a.x, b.y - a.y);
}

/* Append point x (and the kind of the segment that starts at it) to the
 * patch polyline g->pp / g->pf. */
amp_status amp_cp_pp_push(amp_cp_graph *g, amp_vec2 x, unsigned char pseudo)
{
    void *q = g->pp;
    if (amp_grow(g->al, &q, &g->cap_pp, g->npp + 1, sizeof *g->pp) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->pp = q;
    q = g->pf;
    if (amp_grow(g->al, &q, &g->cap_pf, g->npp + 1, sizeof *g->pf) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->pf = q;
    g->pf[g->npp] = pseudo;
    g->pp[g->npp++] = x;
    return AMP_OK;
}

/* The ring points strictly between free ends fi and fj (ring direction):
 * appended to the last path of @p ps, or to the patch polyline g->pp. */
amp_status amp_cp_ring_walk(const amp_polyset *R, const amp_cp_fend *fi, const amp_cp_fend *fj, amp_cp_graph *g, amp_pathset *ps, double z,
                            double rad, amp_error *err)
{
    const amp_vec2 *p = amp_polyset_ring(R, fi->ring);
    size_t n = R->rings[fi->ring].n, s0 = (size_t)fi->pos, s1 = (size_t)fj->pos, s;
    amp_status st;
    if (s1 == s0 && fj->pos >= fi->pos)
        return AMP_OK;
    for (s = (s0 + 1) % n;; s = (s + 1) % n) {
        if (ps) {
            if ((st = amp_pathset_push(ps, amp_v3(p[s].x, p[s].y, z), rad, err)) != AMP_OK)
                return st;
        } else if (amp_cp_pp_push(g, p[s], 0) != AMP_OK)
            return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
        if (s == s1)
            break;
    }
    return AMP_OK;
}

/* Remark 2.1: the unprinted stretch from free end fi to fj as a support path. */
amp_status amp_cp_ring_support(amp_cp_graph *g, const amp_polyset *R, const amp_cp_fend *fi, const amp_cp_fend *fj, amp_pathset *ps,
                               double z, double rad, amp_error *err)
{
    amp_vec2 a = g->v[fi->node], b = g->v[fj->node];
    amp_status st;
    if ((st = amp_pathset_begin(ps, AMP_ROLE_SUPPORT, err)) != AMP_OK ||
        (st = amp_pathset_push(ps, amp_v3(a.x, a.y, z), rad, err)) != AMP_OK ||
        (st = amp_cp_ring_walk(R, fi, fj, g, ps, z, rad, err)) != AMP_OK)
        return st;
    return amp_pathset_push(ps, amp_v3(b.x, b.y, z), rad, err);
}

/* The parameters t in [0, 1] of P + t (Q - P) closer than D to segment AB:
 * the line meets the capsule of AB (convex) in one interval, the hull of its
 * meets with the two end discs and the middle rectangle. 0 if empty. */
static int capsule_interval(amp_vec2 P, amp_vec2 Q, amp_vec2 A, amp_vec2 B, double D, double *lo, double *hi)
{
    double dx = Q.x - P.x, dy = Q.y - P.y, ex = B.x - A.x, ey = B.y - A.y, L = hypot(ex, ey);
    double a0 = HUGE_VAL, a1 = -HUGE_VAL;
    int k;
    for (k = 0; k < 2; k++) {
        /* |P + t d - C|^2 < D^2 */
        amp_vec2 C = k ? B : A;
        double fx = P.x - C.x, fy = P.y - C.y, qa = dx * dx + dy * dy, qb = 2 * (fx * dx + fy * dy),
               qc = fx * fx + fy * fy - D * D, disc = qb * qb - 4 * qa * qc;
        if (qa > 0 && disc > 0) {
            double sq = sqrt(disc);
            a0 = fmin(a0, (-qb - sq) / (2 * qa));
            a1 = fmax(a1, (-qb + sq) / (2 * qa));
        } else if (!(qa > 0) && qc < 0) {
            a0 = fmin(a0, 0.0);
            a1 = fmax(a1, 1.0);
        }
    }
    if (L > 0) {
        /* 0 < (X - A).u < L and |(X - A).n| < D, linear in t */
        double ux = ex / L, uy = ey / L, r0 = -HUGE_VAL, r1 = HUGE_VAL;
        double c[2] = {(P.x - A.x) * ux + (P.y - A.y) * uy, (P.x - A.x) * -uy + (P.y - A.y) * ux};
        double sl[2] = {dx * ux + dy * uy, dx * -uy + dy * ux}, bl[2] = {0, -D}, bh[2] = {L, D};
        for (k = 0; k < 2; k++) {
            if (sl[k] == 0) {
                if (!(c[k] > bl[k] && c[k] < bh[k]))
                    r0 = HUGE_VAL;
                continue;
            }
            {
                double t0 = (bl[k] - c[k]) / sl[k], t1 = (bh[k] - c[k]) / sl[k];
                r0 = fmax(r0, fmin(t0, t1));
                r1 = fmin(r1, fmax(t0, t1));
            }
        }
        if (r0 < r1) {
            a0 = fmin(a0, r0);
            a1 = fmax(a1, r1);
        }
    }
    *lo = fmax(a0, 0.0);
    *hi = fmin(a1, 1.0);
    return *lo < *hi;
}

static int cmp_dbl2(const void *a, const void *b)
{
    const double *x = a, *y = b;
    return x[0] < y[0] ? -1 : (x[0] > y[0] ? 1 : 0);
}

amp_status amp_cp_patchset_alloc(const amp_allocator *al, amp_cp_patchset *P, size_t room)
{
    memset(P, 0, sizeof *P);
    P->a = amp_alloc(al, (room + 1) * sizeof *P->a);
    P->b = amp_alloc(al, (room + 1) * sizeof *P->b);
    P->p0 = amp_alloc(al, (room + 1) * sizeof *P->p0);
    P->np = amp_alloc(al, (room + 1) * sizeof *P->np);
    P->join = amp_alloc(al, room + 1);
    P->box = amp_alloc(al, 4 * (room + 1) * sizeof *P->box);
    return P->a && P->b && P->p0 && P->np && P->join && P->box ? AMP_OK : AMP_ERR_NOMEM;
}

void amp_cp_patchset_free(const amp_allocator *al, amp_cp_patchset *P)
{
    amp_free(al, P->a);
    amp_free(al, P->b);
    amp_free(al, P->p0);
    amp_free(al, P->np);
    amp_free(al, P->join);
    amp_free(al, P->pts);
    amp_free(al, P->box);
}

/* Ring vertices of the patch polyline g->pp closer than 2 µm to the
 * previous kept point or to its end go: the layer code merges vertices
 * under 1 µm apart (below a motor step) path by path, and a Fig. 6 join's
 * two copies (printed, and run back as a pseudo edge) would then lose
 * different vertices next to a free end and interleave there (crossings on
 * the helix with --no-join). Without such points both copies stay one
 * polyline to the last vertex. */
static void micro_filter(amp_cp_graph *g, size_t a, size_t b)
{
    size_t i, w = 1;
    const double tol = 2e-3;
    if (g->npp < 3)
        return;
    /* a patch that would become the straight segment between its ends (R̃ a
     * sliver thinner than tol along a lattice line) keeps its points: the
     * segment would repeat the lattice edge between the same two nodes) */
    for (i = 1; i + 1 < g->npp; i++)
        if (hypot(g->pp[i].x - g->pp[0].x, g->pp[i].y - g->pp[0].y) >= tol &&
            hypot(g->pp[i].x - g->pp[g->npp - 1].x, g->pp[i].y - g->pp[g->npp - 1].y) >= tol)
            break;
    if (i + 1 == g->npp && a < g->nlatv && g->mate && g->mate[a] == b)
        return;
    for (i = 1; i + 1 < g->npp; i++) {
        amp_vec2 l = g->pp[w - 1], x = g->pp[i], e = g->pp[g->npp - 1];
        if (hypot(x.x - l.x, x.y - l.y) < tol || hypot(x.x - e.x, x.y - e.y) < tol)
            continue;
        g->pp[w] = x;
        g->pf[w++] = g->pf[i];
    }
    g->pp[w] = g->pp[g->npp - 1];
    g->pf[w++] = g->pf[g->npp - 1];
    g->npp = w;
}

/* Record the patch from free end fi to fj along the ring (step 5). */
amp_status amp_cp_patch_add(amp_cp_graph *g, amp_cp_patchset *P, const amp_polyset *R, const amp_cp_fend *fi, const amp_cp_fend *fj, int join,
                            amp_error *err)
{
    void *q = P->pts;
    size_t i, k = P->n;
    double *bx = P->box + 4 * k;
    g->npp = 0;
    if (amp_cp_pp_push(g, g->v[fi->node], 0) != AMP_OK || amp_cp_ring_walk(R, fi, fj, g, NULL, 0, 0, err) != AMP_OK ||
        amp_cp_pp_push(g, g->v[fj->node], 0) != AMP_OK ||
        amp_grow(g->al, &q, &P->cap_pts, P->npts + g->npp, sizeof *P->pts) != AMP_OK)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
    P->pts = q;
    micro_filter(g, fi->node, fj->node);
    P->a[k] = fi->node;
    P->b[k] = fj->node;
    P->p0[k] = P->npts;
    P->np[k] = g->npp;
    P->join[k] = (unsigned char)join;
    bx[0] = bx[1] = HUGE_VAL;
    bx[2] = bx[3] = -HUGE_VAL;
    for (i = 0; i < g->npp; i++) {
        P->pts[P->npts++] = g->pp[i];
        bx[0] = fmin(bx[0], g->pp[i].x);
        bx[1] = fmin(bx[1], g->pp[i].y);
        bx[2] = fmax(bx[2], g->pp[i].x);
        bx[3] = fmax(bx[3], g->pp[i].y);
    }
    P->n++;
    return AMP_OK;
}

static amp_status cand_push(amp_cp_graph *g, size_t *ncand, amp_vec2 A, amp_vec2 B)
{
    void *q = g->cand;
    if (amp_grow(g->al, &q, &g->cap_cand, 2 * *ncand + 2, sizeof *g->cand) != AMP_OK)
        return AMP_ERR_NOMEM;
    g->cand = q;
    g->cand[2 * *ncand] = A;
    g->cand[2 * *ncand + 1] = B;
    (*ncand)++;
    return AMP_OK;
}

/* Patch @p self of @p P into g->pp/pf, split into printed and pseudo pieces.
 * Thin boundary cells (§2.2, Figs. 7, 8): a stretch of a patch closer than
 * the bead width D = 2r to a printed edge of the complex that is not
 * adjacent to it — a lattice piece or another patch that does not end at the
 * patch's own free ends — would put material on material; it becomes a
 * pseudo edge (travel inside the stroke, no extrusion). The stretch is
 * bounded by the points where the distance is exactly D, the split points
 * v'_i of Fig. 7; a patch whose cell is unshrinkable (Fig. 8: a parallel
 * edge closer than 2r) becomes pseudo over the whole close stretch. Both
 * patches of a close pair are cut (as both stubs at ṽ_1 in Fig. 7c).
 * D <= 0: no pseudo edges. */
amp_status amp_cp_patch_points(amp_cp_graph *g, const amp_cp_patchset *P, size_t self, double D, amp_error *err)
{
    size_t i, k, ncand = 0, niv, nraw = P->np[self], na = P->a[self], nb = P->b[self];
    const amp_vec2 *raw = P->pts + P->p0[self];
    const double *bs = P->box + 4 * self;
    double bx0 = bs[0] - D, by0 = bs[1] - D, bx1 = bs[2] + D, by1 = bs[3] + D;
    amp_status st = AMP_OK;
    g->npp = 0;
    if (D > 0) {
        /* the printed lattice pieces near the patch, except the stubs at its ends */
        for (i = 0; i < g->nlat && st == AMP_OK; i++) {
            amp_vec2 A = g->v[g->edge_u[i]], B = g->v[g->edge_v[i]];
            if (g->edge_pseudo[i] || g->edge_u[i] == na || g->edge_v[i] == na || g->edge_u[i] == nb ||
                g->edge_v[i] == nb || fmax(A.x, B.x) < bx0 || fmin(A.x, B.x) > bx1 || fmax(A.y, B.y) < by0 ||
                fmin(A.y, B.y) > by1)
                continue;
            st = cand_push(g, &ncand, A, B);
        }
        /* the other patches, except those sharing a free end with this one */
        for (k = 0; k < P->n && st == AMP_OK; k++) {
            const double *bk = P->box + 4 * k;
            const amp_vec2 *q = P->pts + P->p0[k];
            if (k == self || P->a[k] == na || P->a[k] == nb || P->b[k] == na || P->b[k] == nb || bk[2] < bx0 ||
                bk[0] > bx1 || bk[3] < by0 || bk[1] > by1)
                continue;
            for (i = 0; i + 1 < P->np[k] && st == AMP_OK; i++)
                if (!(fmax(q[i].x, q[i + 1].x) < bx0 || fmin(q[i].x, q[i + 1].x) > bx1 ||
                      fmax(q[i].y, q[i + 1].y) < by0 || fmin(q[i].y, q[i + 1].y) > by1))
                    st = cand_push(g, &ncand, q[i], q[i + 1]);
        }
    }
    for (i = 0; i + 1 < nraw && st == AMP_OK; i++) {
        amp_vec2 P0 = raw[i], Q0 = raw[i + 1];
        double t = 0, len = hypot(Q0.x - P0.x, Q0.y - P0.y), tiny = len > 0 ? 1e-9 * D / len : 1.0;
        niv = 0;
        for (k = 0; k < ncand && st == AMP_OK; k++) {
            double lo, hi;
            void *q = g->iv;
            if (!capsule_interval(P0, Q0, g->cand[2 * k], g->cand[2 * k + 1], D, &lo, &hi) || hi - lo <= tiny)
                continue;
            if (amp_grow(g->al, &q, &g->cap_iv, 2 * niv + 2, sizeof *g->iv) != AMP_OK)
                st = AMP_ERR_NOMEM;
            else {
                g->iv = q;
                g->iv[2 * niv] = lo;
                g->iv[2 * niv + 1] = hi;
                niv++;
            }
        }
        if (niv > 1)
            qsort(g->iv, niv, 2 * sizeof *g->iv, cmp_dbl2);
        /* printed [t, lo], pseudo [lo, hi] for each merged close interval */
        if (st == AMP_OK)
            st = amp_cp_pp_push(g, P0, 0);
        for (k = 0; k < niv && st == AMP_OK; k++) {
            double lo = g->iv[2 * k], hi = g->iv[2 * k + 1];
            while (k + 1 < niv && g->iv[2 * k + 2] <= hi)
                hi = fmax(hi, g->iv[2 * ++k + 1]);
            if (hi <= t)
                continue;
            if (lo > t + tiny) /* the split point v' starts the pseudo piece */
                st = amp_cp_pp_push(g, amp_v2(P0.x + lo * (Q0.x - P0.x), P0.y + lo * (Q0.y - P0.y)), 1);
            else
                g->pf[g->npp - 1] = 1;
            t = hi;
            if (st == AMP_OK && hi < 1 - tiny)
                st = amp_cp_pp_push(g, amp_v2(P0.x + hi * (Q0.x - P0.x), P0.y + hi * (Q0.y - P0.y)), 0);
        }
    }
    if (st == AMP_OK && nraw)
        st = amp_cp_pp_push(g, raw[nraw - 1], 0);
    return st == AMP_OK ? AMP_OK : amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory patching a region");
}

/* The patch polyline g->pp as a chain of graph edges from node @p a to node
 * @p b (new nodes in between); every edge pseudo when @p all_pseudo. Two
 * chains built from the same polyline have the same directions at a and b,
 * which the tour's tie rule needs (parallel copies). */
amp_status amp_cp_add_chain(amp_cp_graph *g, size_t a, size_t b, int all_pseudo, double *pseudo_len)
{
    size_t i, prev = a, id;
    for (i = 1; i < g->npp; i++) {
        int ps = all_pseudo || g->pf[i - 1];
        if (i + 1 == g->npp)
            id = b;
        else if (amp_cp_vert(g, g->pp[i], &id) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (amp_cp_edge(g, prev, id, ps) != AMP_OK)
            return AMP_ERR_NOMEM;
        if (ps)
            *pseudo_len += hypot(g->pp[i].x - g->pp[i - 1].x, g->pp[i].y - g->pp[i - 1].y);
        prev = id;
    }
    return AMP_OK;
}
