/* Continuous strokes per island ([P2 §2.2] steps 5-6, §4). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../lib/contpath_internal.h"
#include "fx_meshes.h"
#include "fx_parts.h"
#include "runtool.h"
#include "testutil.h"


/* ---- independent measures on a finished stroke (no code shared with lib/contpath.c) ---- */

static int cmp_pt(const void *a, const void *b)
{
    const amp_vec2 *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    return p->y < q->y ? -1 : (p->y > q->y ? 1 : 0);
}

static double seg_seg_dist(amp_vec2 a, amp_vec2 b, amp_vec2 c, amp_vec2 d)
{
    amp_vec3 A = amp_v3(a.x, a.y, 0), B = amp_v3(b.x, b.y, 0), C = amp_v3(c.x, c.y, 0), D = amp_v3(d.x, d.y, 0);
    double m = fmin(amp_v3_seg_dist2(A, C, D, NULL), amp_v3_seg_dist2(B, C, D, NULL));
    m = fmin(m, fmin(amp_v3_seg_dist2(C, A, B, NULL), amp_v3_seg_dist2(D, A, B, NULL)));
    return sqrt(m); /* the strokes are checked crossing-free separately */
}

/* Paper §2.2 (Figs. 7, 8): beads of the patched complex may overlap only
 * where two edges meet. The stroke is cut into edges: a segment off the rings
 * of R̃ is a lattice edge; consecutive segments on a ring form one patch edge
 * (from free end to free end). Returns the deepest overlap 2r - d over pairs
 * of printed segments of non-adjacent edges (no shared end point), at least
 * one of them on a patch; <= 0 means no material collides. */
static double patch_bead_overlap(const amp_pathset *ps, size_t path, const amp_polyset *reg, double r)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, path);
    size_t n = ps->paths[path].n, i, j, ng = 0;
    size_t *grp = calloc(n + 1, sizeof *grp);
    int *ring = calloc(n + 1, sizeof *ring), *printed = calloc(n + 1, sizeof *printed);
    amp_vec2 *e0 = calloc(n + 1, sizeof *e0), *e1 = calloc(n + 1, sizeof *e1), *fe = calloc(2 * n + 1, sizeof *fe);
    unsigned char *isring = calloc(n + 1, 1);
    double worst = -HUGE_VAL, tol = 1e-7;
    size_t nfe = 0;
    ck_assert(grp && ring && printed && e0 && e1 && fe && isring);
    for (i = 0; i + 1 < n; i++) {
        amp_vec2 a = amp_v2(v[i].p.x, v[i].p.y), b = amp_v2(v[i + 1].p.x, v[i + 1].p.y);
        amp_vec2 mid = amp_v2(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
        ring[i] = amp_polyset_boundary_dist(reg, a) < tol && amp_polyset_boundary_dist(reg, b) < tol &&
                  amp_polyset_boundary_dist(reg, mid) < tol;
        printed[i] = v[i].r > 0 && v[i + 1].r > 0 && (a.x != b.x || a.y != b.y);
    }
    /* free ends: ring points where a lattice segment of the stroke ends */
    for (i = 0; i + 1 < n; i++)
        if (!ring[i] && (v[i].p.x != v[i + 1].p.x || v[i].p.y != v[i + 1].p.y))
            for (j = i; j <= i + 1; j++)
                if (amp_polyset_boundary_dist(reg, amp_v2(v[j].p.x, v[j].p.y)) < tol)
                    fe[nfe++] = amp_v2(v[j].p.x, v[j].p.y);
    if (nfe > 1)
        qsort(fe, nfe, sizeof *fe, cmp_pt);
    /* edges: a lattice segment is one edge; a run of ring segments (with the
     * zero-length steps where the radius changes) is one patch edge, cut at
     * free ends */
    for (i = 0; i + 1 < n; i++) {
        int zero = v[i].p.x == v[i + 1].p.x && v[i].p.y == v[i + 1].p.y;
        amp_vec2 at = amp_v2(v[i].p.x, v[i].p.y);
        if (i > 0 && (ring[i] || zero) && isring[grp[i - 1]] && !bsearch(&at, fe, nfe, sizeof *fe, cmp_pt)) {
            grp[i] = grp[i - 1];
            e1[grp[i]] = amp_v2(v[i + 1].p.x, v[i + 1].p.y);
            continue;
        }
        grp[i] = ng;
        isring[ng] = ring[i] || zero;
        e0[ng] = at;
        e1[ng] = amp_v2(v[i + 1].p.x, v[i + 1].p.y);
        ng++;
    }
    for (i = 0; i + 1 < n; i++) {
        amp_vec2 a = amp_v2(v[i].p.x, v[i].p.y), b = amp_v2(v[i + 1].p.x, v[i + 1].p.y);
        if (!printed[i])
            continue;
        for (j = i + 1; j + 1 < n; j++) {
            amp_vec2 c = amp_v2(v[j].p.x, v[j].p.y), d = amp_v2(v[j + 1].p.x, v[j + 1].p.y);
            size_t g = grp[i], h = grp[j];
            if (!printed[j] || g == h || (!ring[i] && !ring[j]))
                continue;
            if (fmin(a.x, b.x) - 2 * r > fmax(c.x, d.x) || fmax(a.x, b.x) + 2 * r < fmin(c.x, d.x) ||
                fmin(a.y, b.y) - 2 * r > fmax(c.y, d.y) || fmax(a.y, b.y) + 2 * r < fmin(c.y, d.y))
                continue;
            /* adjacent edges: a shared end point */
            if ((e0[g].x == e0[h].x && e0[g].y == e0[h].y) || (e0[g].x == e1[h].x && e0[g].y == e1[h].y) ||
                (e1[g].x == e0[h].x && e1[g].y == e0[h].y) || (e1[g].x == e1[h].x && e1[g].y == e1[h].y))
                continue;
            worst = fmax(worst, 2 * r - seg_seg_dist(a, b, c, d));
        }
    }
    free(grp);
    free(ring);
    free(printed);
    free(e0);
    free(e1);
    free(fe);
    free(isring);
    return worst;
}

/* Nothing dropped: sample points of every K̂ edge strictly inside R̃ lie on
 * the stroke. Returns the number of samples not on it. */
static size_t lattice_samples_missed(const amp_cx2 *khat, const amp_polyset *reg, const amp_pathset *ps, size_t path)
{
    const amp_pvert *v = amp_pathset_path_verts(ps, path);
    size_t n = ps->paths[path].n, f, h, k, i, missed = 0;
    for (f = 0; f < khat->nf; f++)
        for (h = khat->fstart[f]; h < khat->fstart[f + 1]; h++) {
            amp_vec2 A = khat->v[khat->fidx[h]], B = khat->v[khat->fidx[h + 1 < khat->fstart[f + 1] ? h + 1 : khat->fstart[f]]];
            for (k = 0; k < 4; k++) {
                double t = (k + 0.5) / 4;
                amp_vec2 q = amp_v2(A.x + t * (B.x - A.x), A.y + t * (B.y - A.y));
                int on = 0;
                if (amp_polyset_contains(reg, q, 0) != 1 || amp_polyset_boundary_dist(reg, q) < 1e-6)
                    continue;
                for (i = 0; i + 1 < n && !on; i++)
                    on = amp_v3_seg_dist2(amp_v3(q.x, q.y, v[i].p.z), v[i].p, v[i + 1].p, NULL) < 1e-12 &&
                         v[i].r > 0 && v[i + 1].r > 0;
                missed += !on;
            }
        }
    return missed;
}

typedef struct section_fig {
    size_t regions, joins, missed;
    double pseudo_length, infill_length, overlap;
} section_fig;

/* Check every infill stroke of one layer section independently: one closed
 * stroke per region, no crossing, no edge twice, inside the island; with
 * @p fig, also the bead overlap of the patches and the lattice coverage. */
static void check_section_fig(const amp_mesh *m, double z, double r, amp_grid_kind kind, double cell, int pseudo,
                              size_t want_regions, section_fig *fig)
{
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_contpath_stats st;
    amp_cx2 khat;
    amp_polyset P, isl, R, reg;
    amp_pathset ps;
    amp_error err;
    size_t k, q, regions = 0;
    amp_slices_init(&sl, NULL);
    amp_cx2_init(&khat, NULL);
    amp_polyset_init(&P, NULL);
    amp_polyset_init(&isl, NULL);
    amp_polyset_init(&R, NULL);
    amp_polyset_init(&reg, NULL);
    amp_pathset_init(&ps, NULL);
    memset(&st, 0, sizeof st);
    so.layer = 0.5;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(m, &so, &sl, &err), AMP_OK);
    amp_contpath_opts_default(&o, r);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    o.grid = kind;
    o.pseudo_edges = pseudo;
    if (cell > 0)
        o.cell = cell;
    ck_assert_msg(amp_contpath_complex(&sl, &o, &khat, &err) == AMP_OK, "%s", err.msg);
    if (fig) {
        memset(fig, 0, sizeof *fig);
        fig->overlap = -HUGE_VAL;
    }
    ck_assert_int_eq(amp_slice_plane(m, z, &P, NULL, &err), AMP_OK);
    for (k = 0; k < P.nislands; k++) {
        ck_assert_int_eq(amp_polyset_island(&P, k, &isl, &err), AMP_OK);
        ck_assert_int_eq(amp_polyset_inset(&isl, 3 * r, 0, &R, &err), AMP_OK);
        for (q = 0; q < R.nislands; q++) {
            size_t before = ps.npaths, strokes_before = st.strokes;
            amp_stroke_report rep;
            ck_assert_int_eq(amp_polyset_island(&R, q, &reg, &err), AMP_OK);
            ck_assert_msg(amp_contpath_region(&khat, &reg, z, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
            ck_assert_uint_eq(st.strokes - strokes_before, 1); /* exactly one stroke per region */
            ck_assert_uint_eq(ps.npaths - before, 1);
            ck_assert_msg(amp_check_path_stroke(&ps, before, &isl, 1e-9, &rep, &err) == AMP_OK, "z %g: %s", z,
                          err.msg);
            ck_assert(rep.closed);
            ck_assert_uint_gt(rep.segments, 10);
            /* and within the clipping region R̃ itself */
            ck_assert_msg(amp_check_path_stroke(&ps, before, &reg, 1e-7, &rep, &err) == AMP_OK, "%s", err.msg);
            if (fig) {
                fig->overlap = fmax(fig->overlap, patch_bead_overlap(&ps, before, &reg, r));
                fig->missed += lattice_samples_missed(&khat, &reg, &ps, before);
            }
            regions++;
        }
    }
    ck_assert_uint_eq(regions, want_regions);
    ck_assert_uint_eq(st.odd_vertices, 0); /* every vertex even after patching */
    ck_assert_uint_eq(st.multi_stroke, 0);
    ck_assert_uint_gt(st.free_ends, 0);
    ck_assert_uint_eq(st.free_ends % 2, 0); /* handshake lemma */
    if (fig) {
        fig->regions = regions;
        fig->joins = st.joins;
        fig->pseudo_length = st.pseudo_length;
        fig->infill_length = st.infill_length;
    }
    amp_pathset_free(&ps);
    amp_polyset_free(&P);
    amp_polyset_free(&isl);
    amp_polyset_free(&R);
    amp_polyset_free(&reg);
    amp_cx2_free(&khat);
    amp_slices_free(&sl);
}

/* ... and on every section: nothing dropped, no beads of non-adjacent edges overlapping */
static void check_section(const amp_mesh *m, double z, double r, amp_grid_kind kind, size_t want_regions)
{
    section_fig f;
    check_section_fig(m, z, r, kind, 0, 1, want_regions, &f);
    ck_assert_uint_eq(f.missed, 0);
    ck_assert_msg(f.overlap <= 1e-6, "z %g: beads overlap by %g mm", z, f.overlap);
}

START_TEST(torus_sections_get_one_crossing_free_stroke)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 3), 10.0, 3.0, 96, 48), AMP_OK);
    check_section(&m, 3.0, 0.4, AMP_GRID_SQUARE, 1);
    check_section(&m, 1.2, 0.4, AMP_GRID_HEX, 1);
    check_section(&m, 4.5, 0.3, AMP_GRID_TRI, 1);
    amp_mesh_free(&m);
}
END_TEST

/* block with a hole, joined by a 2 mm neck to a second block, and a
 * separate island (2 mm voxels) */
static const char *const plate[] = {
    "##########............####",
    "##########....######..####",
    "##....####....######..####",
    "##....##############..####",
    "##....####....######..####",
    "##########....######..####",
    "##########............####",
    NULL};

START_TEST(plate_with_holes_islands_and_a_thin_neck_gets_one_stroke_per_region)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    /* the neck (2 mm) is narrower than 6r = 2.4 mm: R̃ splits it, so the two
     * islands give three regions, each with its own single stroke */
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 2, 2.0), AMP_OK);
    check_section(&m, 1.0, 0.4, AMP_GRID_SQUARE, 3);
    check_section(&m, 2.0, 0.4, AMP_GRID_HEX, 3); /* plane through mesh vertices */
    check_section(&m, 3.0, 0.35, AMP_GRID_TRI, 3);
    check_section(&m, 3.0, 0.3, AMP_GRID_TRI, 2); /* 6r = 1.8 mm: the neck carries infill */
    amp_mesh_free(&m);
}
END_TEST

/* a perforated plate: 15 holes, more rings than the exhaustive pairing
 * search takes (greedy choice per ring); the lattice lines fall exactly on
 * the inset's straight edges (vertices on the boundary are nudged off) */
static const char *const sieve[] = {
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    "#..#..#..#..#..##",
    "#..#..#..#..#..##",
    "#################",
    NULL};

START_TEST(perforated_plate_with_many_holes_gets_one_stroke)
{
    amp_mesh m;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, sieve, 1, 3.0), AMP_OK);
    check_section(&m, 1.5, 0.25, AMP_GRID_SQUARE, 1);
    amp_mesh_free(&m);
}
END_TEST

/* Fig. 6: with the hexagonal lattice the alternating pairings of the 16
 * rings cannot link every piece (before the joins: 3 strokes); neighbouring
 * components are joined along R̃, so the region gets one stroke and every
 * lattice piece inside R̃ is printed (nothing dropped). */
START_TEST(perforated_plate_hex_lattice_joins_its_components_into_one_stroke)
{
    amp_mesh m;
    section_fig f;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, sieve, 1, 3.0), AMP_OK);
    check_section_fig(&m, 1.5, 0.25, AMP_GRID_HEX, 0, 1, 1, &f); /* asserts one stroke, checker passes */
    ck_assert_uint_gt(f.joins, 0);    /* the pairings alone left components apart */
    ck_assert_uint_eq(f.missed, 0);   /* every lattice sample inside R̃ is printed */
    ck_assert_double_le(f.overlap, 1e-6);
    /* also without pseudo edges: still one stroke, nothing dropped */
    check_section_fig(&m, 1.5, 0.25, AMP_GRID_HEX, 0, 0, 1, &f);
    ck_assert_uint_gt(f.joins, 0);
    ck_assert_uint_eq(f.missed, 0);
    amp_mesh_free(&m);
}
END_TEST

/* an L-shaped bar 3 voxels (6 mm) wide: with r = 0.4 the infill region R̃
 * is 3.6 mm wide, about one lattice cell */
static const char *const ell[] = {
    "###.........",
    "###.........",
    "###.........",
    "###.........",
    "############",
    "############",
    "############",
    NULL};

/* Figs. 7, 8: cells cut thin at the boundary of R̃ put patches closer than
 * the bead width 2r to lattice edges (or to other patches) that they do not
 * meet. Without pseudo edges the beads overlap by up to ~2r; with them no
 * two printed beads of non-adjacent edges overlap, every region still has
 * one stroke, and the lattice itself stays printed. */
START_TEST(thin_boundary_cells_become_pseudo_edges_so_beads_do_not_collide)
{
    static const struct {
        int torus;
        amp_grid_kind kind;
        double cell;
    } cases[] = {{0, AMP_GRID_SQUARE, 4.0}, {0, AMP_GRID_HEX, 3.0}, {0, AMP_GRID_TRI, 3.5},
                 {1, AMP_GRID_SQUARE, 3.5}, {1, AMP_GRID_HEX, 4.0}, {1, AMP_GRID_TRI, 3.0}};
    amp_mesh m, t;
    section_fig f, f0;
    size_t c;
    double r = 0.4;
    amp_mesh_init(&m, NULL);
    amp_mesh_init(&t, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, ell, 1, 2.0), AMP_OK);
    ck_assert_int_eq(fx_torus(&t, amp_v3(0, 0, 3), 10.0, 3.0, 96, 48), AMP_OK);
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const amp_mesh *g = cases[c].torus ? &t : &m;
        double z = cases[c].torus ? 3.0 : 1.0;
        check_section_fig(g, z, r, cases[c].kind, cases[c].cell, 0, 1, &f0);
        check_section_fig(g, z, r, cases[c].kind, cases[c].cell, 1, 1, &f);
        ck_assert_msg(f0.overlap > 0.25 * r, "case %lu: no thin cell without pseudo edges (%g)", (unsigned long)c,
                      f0.overlap);
        ck_assert_msg(f.overlap <= 1e-6, "case %lu: beads overlap by %g mm", (unsigned long)c, f.overlap);
        ck_assert_double_gt(f.pseudo_length, 0);
        ck_assert_double_lt(f.pseudo_length, 0.25 * f.infill_length);
        ck_assert_uint_eq(f.missed, 0);
        ck_assert_uint_eq(f0.missed, 0);
    }
    amp_mesh_free(&m);
    amp_mesh_free(&t);
}
END_TEST

START_TEST(all_layers_of_a_sphere_and_torus_pair)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_contpath_stats st;
    amp_pathset ps;
    amp_error err;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 3), 10.0, 3.0, 64, 32), AMP_OK);
    ck_assert_int_eq(fx_sphere(&m, amp_v3(22, 0, 4), 4.0, 48, 24), AMP_OK);
    so.layer = 0.5;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
    amp_contpath_opts_default(&o, 0.4);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(st.layers, sl.nlayers);
    ck_assert_uint_gt(st.islands, sl.nlayers); /* two bodies on most layers */
    ck_assert_uint_ge(st.strokes, st.regions);
    ck_assert_uint_eq(st.odd_vertices, 0);
    /* perimeters and region strokes joined: one closed path per island */
    ck_assert_uint_eq(ps.npaths, st.islands);
    ck_assert_uint_eq(st.island_strokes, st.islands);
    ck_assert_uint_eq(st.travel_moves, ps.npaths - 1);
    ck_assert(st.printed_length > st.infill_length && st.infill_length > 0);
    /* pseudo edges are in the paths but print nothing */
    ck_assert_near(st.printed_length + st.pseudo_length, amp_pathset_length(&ps, AMP_ROLE_OBJECT), 1e-6);
    /* Remark 2.1: stretches printed separately as support */
    amp_pathset_clear(&ps);
    o.support_stretches = 1;
    ck_assert_int_eq(amp_contpath_layers(&sl, &o, &ps, &st, &err), AMP_OK);
    ck_assert_uint_gt(st.support_paths, 0);
    ck_assert_near(st.support_length, amp_pathset_length(&ps, AMP_ROLE_SUPPORT), 1e-6);
    ck_assert_near(st.unprinted_length, 0, 0);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(built_in_models_get_one_crossing_free_stroke_per_island)
{
    static const char *const names[] = {"helix", "twisted-bridge"};
    size_t n, i;
    for (n = 0; n < 2; n++) {
        amp_mesh m;
        amp_slices sl;
        amp_slice_opts so;
        amp_contpath_opts o;
        amp_contpath_stats st;
        amp_pathset ps;
        amp_error err;
        amp_mesh_init(&m, NULL);
        amp_slices_init(&sl, NULL);
        amp_pathset_init(&ps, NULL);
        ck_assert_msg(amp_mesh_model(names[n], 0, &m, &err) == AMP_OK, "%s", err.msg);
        so.layer = 1.0;
        so.first_layer = 0.4;
        ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
        ck_assert_uint_eq(sl.open_chains, 0);
        amp_contpath_opts_default(&o, 0.5);
        o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
        ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
        ck_assert_uint_gt(st.islands, sl.nlayers / 2);
        /* a region's components are spliced to the perimeter, not joined inside it (Fig. 6) */
        ck_assert_uint_ge(st.strokes, st.regions);
        ck_assert_uint_eq(st.island_strokes, st.islands);
        ck_assert_uint_eq(st.odd_vertices, 0);
        /* pseudo edges (thin cells, return runs of joins) are a small part of the infill */
        ck_assert_msg(st.pseudo_length <= 0.1 * st.infill_length, "%s: pseudo %g of %g mm", names[n],
                      st.pseudo_length, st.infill_length);
        ck_assert_near(st.printed_length + st.pseudo_length, amp_pathset_length(&ps, AMP_ROLE_OBJECT), 1e-6);
        for (i = 0; i < ps.npaths; i++)
            ck_assert_msg(amp_check_path_stroke(&ps, i, NULL, 0, NULL, &err) == AMP_OK, "%s path %lu: %s", names[n],
                          (unsigned long)i, err.msg);
        amp_pathset_free(&ps);
        amp_slices_free(&sl);
        amp_mesh_free(&m);
    }
}
END_TEST

START_TEST(stroke_checker_rejects_crossings_repeats_and_escapes)
{
    amp_polyset sq;
    amp_stroke_report rep;
    amp_error err;
    amp_vec2 box[4] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
    amp_vec2 bowtie[5] = {{1, 1}, {9, 9}, {9, 1}, {1, 9}, {1, 1}};
    amp_vec2 twice[6] = {{1, 1}, {5, 1}, {5, 5}, {1, 1}, {5, 1}, {1, 1}};
    amp_vec2 escape[4] = {{1, 1}, {12, 1}, {1, 5}, {1, 1}};
    /* figure eight touching at (5,5): the passes cross there */
    amp_vec2 eight[7] = {{5, 5}, {8, 8}, {8, 2}, {5, 5}, {2, 8}, {2, 2}, {5, 5}};
    /* two loops touching at (5,5) without crossing */
    amp_vec2 touch[7] = {{5, 5}, {8, 2}, {8, 8}, {5, 5}, {2, 8}, {2, 2}, {5, 5}};
    /* loop (1,1)-(5,1)-(5,5)-(1,1) with a spur (5,1)-(8,1) printed out and run back */
    amp_vec2 back[8] = {{1, 1}, {5, 1}, {8, 1}, {8, 1}, {5, 1}, {5, 1}, {5, 5}, {1, 1}};
    double back_r[8] = {0.4, 0.4, 0.4, 0, 0, 0.4, 0.4, 0.4};
    double twice_r[8] = {0.4, 0.4, 0.4, 0.4, 0.4, 0.4, 0.4, 0.4};
    double bowtie_r[5] = {0.4, 0.4, 0, 0, 0.4};
    double escape_r[4] = {0.4, 0, 0, 0.4};
    amp_polyset_init(&sq, NULL);
    ck_assert_int_eq(amp_polyset_add(&sq, box, 4, NULL), AMP_OK);
    ck_assert_int_eq(amp_check_stroke(bowtie, 5, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(rep.crossings, 1);
    ck_assert_int_eq(amp_check_stroke(twice, 6, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.repeated_edges, 0);
    ck_assert_int_eq(amp_check_stroke(escape, 4, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.outside, 0);
    ck_assert_int_eq(amp_check_stroke(eight, 7, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(rep.crossings, 1);
    ck_assert_msg(amp_check_stroke(touch, 7, &sq, 0, &rep, &err) == AMP_OK, "%s", err.msg);
    ck_assert(rep.closed);
    /* a printed stretch run back as a pseudo edge (radius 0, with the vertex
     * written twice where the radius changes): no material twice */
    ck_assert_int_eq(amp_check_stroke(back, 8, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.repeated_edges, 0);
    ck_assert_msg(amp_check_stroke_radii(back, back_r, 8, &sq, 0, &rep, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(rep.pseudo, 1);
    ck_assert_uint_eq(rep.repeated_edges, 0);
    /* ... but printed twice it fails, and a pseudo edge must not cross */
    ck_assert_int_eq(amp_check_stroke_radii(back, twice_r, 8, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.repeated_edges, 0);
    ck_assert_int_eq(amp_check_stroke_radii(bowtie, bowtie_r, 5, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_eq(rep.crossings, 1);
    /* and it must stay inside the region */
    ck_assert_int_eq(amp_check_stroke_radii(escape, escape_r, 4, &sq, 0, &rep, &err), AMP_ERR_CHECK);
    ck_assert_uint_gt(rep.outside, 0);
    amp_polyset_free(&sq);
}
END_TEST

/* Proper crossings among the segments of a polyline, pair by pair (segments that share an end excluded):
 * the reference for the checker's strips. */
static size_t crossings_by_pairs(const amp_vec2 *p, size_t n)
{
    size_t i, j, c = 0;
    for (i = 0; i + 1 < n; i++)
        for (j = i + 2; j + 1 < n; j++) {
            double o1 = amp_v2_orient(p[i], p[i + 1], p[j]), o2 = amp_v2_orient(p[i], p[i + 1], p[j + 1]);
            double o3 = amp_v2_orient(p[j], p[j + 1], p[i]), o4 = amp_v2_orient(p[j], p[j + 1], p[i + 1]);
            c += o1 * o2 < 0 && o3 * o4 < 0;
        }
    return c;
}

/*
 * A stroke of thousands of segments is swept in horizontal strips (lib/check_stroke.c): every crossing is
 * still counted once. A random walk, random jumps (long segments spanning many strips), a tall jittered
 * zigzag (so many strip entries that the plain sweep runs instead), and a staircase without crossings. Counting a pair in every strip it shares, or
 * missing the pairs whose overlap begins in a strip below one segment's low end, fails this.
 */
START_TEST(stroke_checker_counts_every_crossing_of_a_long_stroke_once)
{
    amp_polyset box;
    amp_stroke_report rep;
    amp_error err;
    amp_vec2 corners[4] = {{-1, -1}, {101, -1}, {101, 101}, {-1, 101}}, *p = malloc(3001 * sizeof *p);
    unsigned long s = 12345;
    size_t n, k, ref;
    int shape;
    ck_assert_ptr_nonnull(p);
    amp_polyset_init(&box, NULL);
    ck_assert_int_eq(amp_polyset_add(&box, corners, 4, NULL), AMP_OK);
    for (shape = 0; shape < 4; shape++) {
        n = shape == 2 ? 3001 : shape == 3 ? 3000 : 1500;
        for (k = 0; k < n; k++) {
            s = s * 6364136223846793005UL + 1442695040888963407UL;
            if (shape == 2) /* a staircase: never crosses itself */
                p[k] = amp_v2(0.03 * (double)((k + 1) / 2), 0.03 * (double)(k / 2));
            else if (shape == 3) /* tall zigzag, jittered: every segment through every strip (the plain sweep) */
                p[k] = amp_v2(0.01 * (double)k + (double)(s >> 11) / 9007199254740992.0 * 0.06, k % 2 ? 100 : 0);
            else if (shape == 0) { /* steps of up to 5 mm, reflected at the sides of a 100 mm square */
                double x = k ? p[k - 1].x + (double)(s >> 11) / 9007199254740992.0 * 10 - 5 : 50;
                double y = k ? p[k - 1].y + (double)((s * 2862933555777941757UL) >> 11) / 9007199254740992.0 * 10 - 5 : 50;
                p[k] = amp_v2(x < 0 ? -x : x > 100 ? 200 - x : x, y < 0 ? -y : y > 100 ? 200 - y : y);
            } else { /* anywhere in the square: long segments through many strips */
                p[k] = amp_v2((double)(s >> 11) / 9007199254740992.0 * 100,
                              (double)((s * 2862933555777941757UL) >> 11) / 9007199254740992.0 * 100);
            }
        }
        ref = crossings_by_pairs(p, n);
        ck_assert_int_eq(amp_check_stroke(p, n, &box, 0, &rep, &err), ref ? AMP_ERR_CHECK : AMP_OK);
        ck_assert_uint_eq(rep.crossings, ref);
        ck_assert_uint_eq(rep.segments, n - 1);
        if (shape != 2)
            ck_assert_uint_gt(ref, 100);
    }
    amp_polyset_free(&box);
    free(p);
}
END_TEST

START_TEST(printer_profile_sets_the_bead_width_of_a_continuous_slice)
{
    /* docs/interfaces.md §4: beads 1.125 x the profile's nozzle; --radius still wins */
    amp_mesh m;
    amp_error err;
    char args[768], out[4096];
    const char *stl = fx_tmp("pplate.stl"), *amp = fx_tmp("pplate.amp"), *ini = fx_tmp("p06.ini");
    FILE *f = fopen(ini, "w");
    ck_assert_ptr_nonnull(f);
    fputs("# a PrusaSlicer printer with a 0.6 mm nozzle\nnozzle_diameter = 0.6,0.6\nbed_shape = 0x0,250x0,250x210,0x210\n", f);
    fclose(f);
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 3, 2.0), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --printer %s --json -o %s", stl, ini, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"radius\":0.3375") != NULL, "%s", out);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --printer %s --radius 0.3 --json -o %s", stl, ini, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"radius\":0.3,") != NULL, "%s", out);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --printer no-such-printer -o %s", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 2);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(cli_continuous_gives_one_stroke_per_island_and_check_agrees)
{
    amp_mesh m;
    amp_error err;
    char args[768], out[4096];
    const char *stl = fx_tmp("plate.stl"), *amp = fx_tmp("plate.amp");
    FILE *f;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxel_picture(&m, plate, 3, 2.0), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --radius 0.4 --continuous -o %s --json", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    /* 12 layers x 2 islands x one stroke; 3 regions per layer (the neck splits R̃) */
    ck_assert_msg(strstr(out, "\"layers\":12,\"empty_layers\":0,\"islands\":24,") != NULL, "%s", out);
    /* the 12 solid regions are strip lattices: one stroke per strip, joined
     * into the island's one stroke; the sparse regions are one stroke each */
    ck_assert_msg(strstr(out, "\"island_strokes\":24,\"specks\":0,\"extrusion_starts\":24,\"regions\":36,"
                              "\"skin_regions\":12,") != NULL &&
                      strstr(out, "\"multi_stroke_regions\":12,") != NULL,
                  "%s", out);
    ck_assert_msg(strstr(out, "\"crossings\":0,\"repeated_edges\":0") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"odd_vertices\":0") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"joins\":") != NULL && strstr(out, "\"pseudo_length_mm\":") != NULL, "%s", out);
    /* the G-code writer takes the pseudo edges (radius 0) as moves without extrusion */
    snprintf(args, sizeof args, "gcode %s -o %s.gcode", amp, amp);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    snprintf(args, sizeof args, "%s.gcode", amp);
    remove(args);
    snprintf(args, sizeof args, "check %s --mesh %s --layer 0.5 --json", amp, stl);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"ok\":true") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"pseudo_segments\":") != NULL, "%s", out);
    /* a crossing path appended: the check fails with exit 1 */
    f = fopen(amp, "a");
    ck_assert(f != NULL);
    fprintf(f, "path object 5\n1 1 0.5 0.4\n9 9 0.5 0.4\n9 1 0.5 0.4\n1 9 0.5 0.4\n1 1 0.5 0.4\n");
    fclose(f);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 1);
    ck_assert_msg(strstr(out, "\"crossings\":1") != NULL, "%s", out);
    snprintf(args, sizeof args, "slice %s --layer 0.5 --continuous --grid octagon", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 2);
    remove(stl);
    remove(amp);
    amp_mesh_free(&m);
}
END_TEST


/* ---- real parts (fewer starts than a slicer): counted from the G-code text, not the library ---- */

/* Extrusion starts per layer height in a G-code file: an extruding move
 * (XY change with E growing) after a move without extrusion (XY or Z). Returns the
 * number of distinct heights written into z[] / starts[] (at most cap). */
static size_t gcode_starts(const char *file, double *z, size_t *starts, size_t cap, double *first_z)
{
    FILE *f = fopen(file, "r");
    char line[512];
    double X = 0, Y = 0, Z = 0, E = 0;
    int rel = 0, printing = 0;
    size_t nz = 0, k;
    ck_assert(f != NULL);
    *first_z = -1;
    while (fgets(line, sizeof line, f)) {
        double x = X, y = Y, zz = Z, e = E, v;
        char *p;
        int has_e = 0;
        if (strncmp(line, "M83", 3) == 0)
            rel = 1;
        if (strncmp(line, "M82", 3) == 0)
            rel = 0;
        if (strncmp(line, "G92", 3) == 0 && (p = strchr(line, 'E')) != NULL)
            E = atof(p + 1);
        if (strncmp(line, "G0 ", 3) != 0 && strncmp(line, "G1 ", 3) != 0)
            continue;
        if ((p = strchr(line, ';')) != NULL)
            *p = 0;
        for (p = line + 3; *p; p++) {
            if (p[-1] != ' ')
                continue;
            v = atof(p + 1);
            if (*p == 'X')
                x = v;
            else if (*p == 'Y')
                y = v;
            else if (*p == 'Z')
                zz = v;
            else if (*p == 'E') {
                e = rel ? E + v : v;
                has_e = 1;
            }
        }
        if (x != X || y != Y || zz != Z) { /* a move; a Z-only move (layer change) never extrudes */
            int extrudes = (x != X || y != Y) && has_e && e > E + 1e-9;
            if (extrudes && !printing) {
                for (k = 0; k < nz && fabs(z[k] - zz) > 1e-6; k++)
                    ;
                if (k == nz) {
                    ck_assert_uint_lt(nz, cap);
                    z[nz] = zz;
                    starts[nz++] = 0;
                }
                starts[k]++;
                if (*first_z < 0)
                    *first_z = zz;
            }
            printing = extrudes;
        }
        X = x;
        Y = y;
        Z = zz;
        E = e;
    }
    fclose(f);
    return nz;
}

/* Every layer of the mesh in @p stl sliced at @p layer: as many extrusion
 * starts in the G-code as the section has islands (one stroke per island),
 * the check of every path clean, and the first bead on the lowest layer.
 * @p out receives the JSON of slice --continuous. */
static void stl_one_start_per_island(const char *stl, const char *name, double layer, char *out, size_t cap)
{
    static double z[4096];
    static size_t starts[4096];
    char args[2048], amp[400], gc[420], json[1 << 14];
    const char *q;
    size_t nz, k, islands_total = 0, starts_total = 0;
    double first_z;
    snprintf(amp, sizeof amp, "%s.amp", stl);
    snprintf(gc, sizeof gc, "%s.gcode", amp);
    snprintf(args, sizeof args, "slice %s --layer %g --continuous -o %s --json", stl, layer, amp);
    ck_assert_msg(fx_run_tool(args, json, sizeof json) == 0, "%s: %s", name, json);
    ck_assert_msg(strstr(json, "\"crossings\":0,\"repeated_edges\":0,\"outside\":0,\"failed_paths\":0") != NULL,
                  "%s", json);
    ck_assert_msg(strstr(json, "\"empty_layers\":0,") != NULL, "%s", json);
    if (out)
        snprintf(out, cap, "%s", json);
    snprintf(args, sizeof args, "gcode %s -o %s", amp, gc);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    nz = gcode_starts(gc, z, starts, 4096, &first_z);
    /* islands per layer from the sections themselves (slice --polygons) */
    {
        static char pol[1 << 17];
        snprintf(args, sizeof args, "slice %s --layer %g --polygons --json", stl, layer);
        ck_assert_int_eq(fx_run_tool(args, pol, sizeof pol), 0);
        for (q = strstr(pol, "\"z_print\":"); q; q = strstr(q + 1, "\"z_print\":")) {
            double zp = atof(q + 10);
            long isl = atol(strstr(q, "\"islands\":") + 10);
            size_t got = 0;
            for (k = 0; k < nz; k++)
                if (fabs(z[k] - zp) < 1e-3)
                    got = starts[k];
            ck_assert_msg(got == (size_t)isl, "%s: layer at z %g has %ld islands and %lu extrusion starts", name, zp,
                          isl, (unsigned long)got);
            islands_total += (size_t)isl;
        }
    }
    for (k = 0; k < nz; k++)
        starts_total += starts[k];
    ck_assert_uint_eq(starts_total, islands_total);
    /* the first bead is laid on the lowest layer, nothing below it */
    for (k = 0; k < nz; k++)
        ck_assert(z[k] >= first_z - 1e-9);
    remove(amp);
    remove(gc);
}

static void part_one_start_per_island(fx_part part, double step)
{
    amp_mesh m;
    amp_error err;
    char name[64], stl[400];
    snprintf(name, sizeof name, "%s.stl", fx_part_name(part));
    snprintf(stl, sizeof stl, "%s", fx_tmp(name));
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, part, step), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    amp_mesh_free(&m);
    stl_one_start_per_island(stl, fx_part_name(part), 0.2, NULL, 0);
    remove(stl);
}

START_TEST(torus_and_idler_get_one_extrusion_start_per_island_counted_in_the_gcode)
{
    part_one_start_per_island(FX_PART_TORUS, 0.8);
    part_one_start_per_island(FX_PART_IDLER, 0.7);
}
END_TEST

START_TEST(screw_bunny_and_open_mesh_get_one_extrusion_start_per_island_counted_in_the_gcode)
{
    part_one_start_per_island(FX_PART_SCREW, 0.5);
    part_one_start_per_island(FX_PART_BUNNY, 0.6);
    part_one_start_per_island(FX_PART_OPEN, 0.6);
}
END_TEST

/* Slice a part in the library with the defaults (0.45 mm beads). */
static void layers_of(fx_part part, double step, double layer, double first, amp_slices *sl, amp_pathset *ps,
                      amp_contpath_stats *st, const amp_contpath_opts *o)
{
    amp_mesh m;
    amp_slice_opts so;
    amp_error err;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, part, step), AMP_OK);
    so.layer = layer;
    so.first_layer = first;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, sl, &err), AMP_OK);
    ck_assert_msg(amp_contpath_layers(sl, o, ps, st, &err) == AMP_OK, "%s", err.msg);
    amp_mesh_free(&m);
}

/* A caller's allocator (not the default one): amp_contpath_layers then makes every island on the calling
 * thread, the reference the OpenMP threads' output must equal. */
static void *calling_alloc(void *u, size_t n)
{
    (*(long *)u)++;
    return malloc(n);
}
static void *calling_realloc(void *u, void *p, size_t n)
{
    (*(long *)u)++;
    return realloc(p, n);
}
static void calling_free(void *u, void *p)
{
    (void)u;
    free(p);
}

/* Pillars on every other cell: a layer of 400 islands, more than the library makes at once. */
static int every_other_cell(int i, int j, int k, void *u)
{
    (void)k;
    (void)u;
    return i % 2 == 0 && j % 2 == 0;
}

/* Slice @p m and compare the paths and figures made with the default allocator (the islands on the OpenMP
 * threads when built with them) with those made with a caller's allocator (on the calling thread). */
static void same_paths_on_any_thread(const amp_mesh *m, const amp_contpath_opts *o, size_t *islands)
{
    long calls = 0;
    amp_allocator ca;
    amp_slices sl;
    amp_slice_opts so;
    amp_pathset a, b;
    amp_contpath_stats sa, sb;
    amp_error err;
    ca.alloc = calling_alloc;
    ca.realloc = calling_realloc;
    ca.free = calling_free;
    ca.user = &calls;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, &ca);
    so.layer = 0.2;
    so.first_layer = 0.2;
    ck_assert_int_eq(amp_slice_mesh(m, &so, &sl, &err), AMP_OK);
    ck_assert_msg(amp_contpath_layers(&sl, o, &a, &sa, &err) == AMP_OK, "%s", err.msg);
    ck_assert_msg(amp_contpath_layers(&sl, o, &b, &sb, &err) == AMP_OK, "%s", err.msg);
    ck_assert_int_gt(calls, 0);
    ck_assert_uint_gt(a.npaths, 0);
    fx_assert_same_paths(&a, &b);
    ck_assert(memcmp(&sa, &sb, sizeof sa) == 0);
    *islands = sa.islands;
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_slices_free(&sl);
}

/* Distance from (x, y) to the segment (ax, ay)-(bx, by). */
static double seg_dist2d(double x, double y, double ax, double ay, double bx, double by)
{
    double dx = bx - ax, dy = by - ay, t = ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(x - ax - t * dx, y - ay - t * dy);
}

/* A flat 0.4 mm plate like a recycling symbol's arrows: three arms 2 mm wide, two meeting at a chevron,
 * all slanting across the lattice (without the cap: 1.13 and 1.16 x the slab on its two layers). */
static double chevron_f(amp_vec3 p, void *u)
{
    double a = seg_dist2d(p.x, p.y, 0, 0, 5.657, 5.657) - 1, b = seg_dist2d(p.x, p.y, 0, 0, 5.657, -5.657) - 1;
    double c = seg_dist2d(p.x, p.y, -1, 5, 5, 9) - 1;
    (void)u;
    return fmax(fmin(fmin(a, b), c), fabs(p.z - 0.2) - 0.2);
}

/* Bead volume of the paths at height z (the planar cross-section of amp_bead_area, mean radius per segment). */
static double layer_bead_volume(const amp_pathset *ps, double z)
{
    size_t i, k;
    double v = 0;
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *p = amp_pathset_path_verts(ps, i);
        if (!ps->paths[i].n || fabs(p[0].p.z - z) > 1e-9)
            continue;
        for (k = 1; k < ps->paths[i].n; k++)
            v += amp_bead_area(0.5 * (p[k - 1].r + p[k].r), ps->paths[i].h) * amp_v3_dist(p[k - 1].p, p[k].p);
    }
    return v;
}

/*
 * Where beads overlap (a lattice clipped to slanting arms, a perimeter meeting itself across a strip
 * narrower than two beads) the plastic of a layer would exceed the volume of its slab: the overlap cap
 * narrows the island's beads to it. Measured here from the paths and the sections, layer by layer; the
 * same plate without the cap overfills, so the test fails if the cap is removed.
 */
START_TEST(beads_that_overlap_are_narrowed_to_the_volume_of_their_slab)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    amp_error err;
    double worst[2] = {0, 0};
    int cap;
    size_t i;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_implicit(&m, chevron_f, NULL, amp_v3(-3, -9, -0.05), amp_v3(10, 11, 0.45), 0.1), AMP_OK);
    so.layer = 0.2;
    so.first_layer = 0.2;
    amp_slices_init(&sl, NULL);
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
    ck_assert_uint_eq(sl.nlayers, 2);
    for (cap = 0; cap < 2; cap++) {
        amp_contpath_opts_default(&o, 0.225);
        o.overlap_cap = cap;
        amp_pathset_init(&ps, NULL);
        ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
        for (i = 0; i < sl.nlayers; i++) {
            double slab = amp_polyset_area(&sl.layers[i].polys) * 0.2, v = layer_bead_volume(&ps, sl.layers[i].z_print);
            ck_assert_double_gt(v, 0.8 * slab); /* narrowed, not emptied */
            worst[cap] = fmax(worst[cap], v / slab);
        }
        if (cap)
            ck_assert_uint_gt(st.narrowed_islands, 0);
        else
            ck_assert_uint_eq(st.narrowed_islands, 0);
        amp_pathset_free(&ps);
    }
    ck_assert_msg(worst[0] > 1.05, "without the cap the beads fill %g x their slab", worst[0]);
    ck_assert_msg(worst[1] <= 1.0 + 1e-9, "with the cap the beads fill %g x their slab", worst[1]);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(islands_made_on_many_threads_equal_those_made_on_one)
{
    amp_mesh m;
    amp_contpath_opts o;
    size_t islands = 0;
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool, band retries included */
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, FX_PART_IDLER, 0.8), AMP_OK);
    same_paths_on_any_thread(&m, &o, &islands);
    ck_assert_uint_gt(islands, 10);
    amp_mesh_free(&m);
    /* 20 x 20 pillars of 1 mm, 1 mm tall: 5 layers of 400 islands each, every one printed */
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_voxels(&m, 39, 39, 1, 1.0, every_other_cell, NULL), AMP_OK);
    same_paths_on_any_thread(&m, &o, &islands);
    ck_assert_uint_eq(islands, 5 * 400);
    amp_mesh_free(&m);
}
END_TEST

START_TEST(paths_carry_their_layer_bead_height_and_start_where_the_nozzle_is)
{
    amp_slices sl;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    size_t i, k;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    layers_of(FX_PART_IDLER, 0.8, 0.2, 0.3, &sl, &ps, &st, &o);
    ck_assert_uint_gt(ps.npaths, 10);
    for (i = 0; i < ps.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&ps, i);
        double z = v[0].p.z;
        /* first layer 0.3 thick, then 0.2 */
        ck_assert_msg(fabs(ps.paths[i].h - (fabs(z - 0.3) < 1e-9 ? 0.3 : 0.2)) < 1e-9, "path %lu at z %g: h %g",
                      (unsigned long)i, z, ps.paths[i].h);
        ck_assert_double_gt(amp_path_length(&ps, i), 0); /* no zero-length path */
        if (i > 0) {
            /* a closed stroke starts at its printed vertex nearest to the previous end */
            const amp_pvert *pv = amp_pathset_path_verts(&ps, i - 1);
            amp_vec3 e = pv[ps.paths[i - 1].n - 1].p;
            double d0 = hypot(v[0].p.x - e.x, v[0].p.y - e.y);
            for (k = 1; k + 1 < ps.paths[i].n; k++)
                if (v[k].r > 0 && v[k - 1].r > 0 && v[k + 1].r > 0)
                    ck_assert(hypot(v[k].p.x - e.x, v[k].p.y - e.y) >= d0 - 1e-9);
        }
    }
    ck_assert_uint_eq(st.island_strokes, st.islands);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
}
END_TEST

START_TEST(cycle_tree_and_merging_trace_the_same_edges_once_without_crossing)
{
    /* §4: the cycle-tree traversal (Hierholzer on the boundary cycles,
     * q = 2 / q > 2 splices) and the older merging must both run every edge
     * of the patched complex exactly once: same printed length, no edge
     * twice, no crossing; the cycle tree has many levels on a wide part */
    amp_slices sl, sl2;
    amp_pathset a, b;
    amp_contpath_stats sa, sb;
    amp_contpath_opts o;
    amp_error err;
    size_t i;
    amp_slices_init(&sl, NULL);
    amp_slices_init(&sl2, NULL);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    layers_of(FX_PART_TORUS, 0.9, 0.5, 0, &sl, &a, &sa, &o);
    o.tour = AMP_TOUR_MERGE;
    layers_of(FX_PART_TORUS, 0.9, 0.5, 0, &sl2, &b, &sb, &o);
    ck_assert_uint_eq(sa.tour_fallbacks, 0);
    ck_assert_uint_gt(sa.tree_levels, 3);
    ck_assert_uint_gt(sa.cycles, sa.regions);
    ck_assert_uint_eq(sa.strokes, sb.strokes);
    ck_assert_double_eq_tol(sa.infill_length, sb.infill_length, 1e-6 * sa.infill_length);
    ck_assert_uint_eq(a.npaths, sa.islands);
    for (i = 0; i < a.npaths; i++)
        ck_assert_msg(amp_check_path_stroke(&a, i, NULL, 0, NULL, &err) == AMP_OK, "path %lu: %s", (unsigned long)i,
                      err.msg);
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_slices_free(&sl);
    amp_slices_free(&sl2);
}
END_TEST

static double vee_f(amp_vec3 p, void *u)
{
    (void)u;
    /* a prism standing on its ridge: the first sections are thinner than a bead */
    return fmax(fmax(fabs(p.x) - 0.8 * p.z, p.z - 4), fabs(p.y) - 6);
}

START_TEST(a_sliver_first_layer_is_printed_on_the_bed)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    amp_error err;
    size_t i, first_layer_paths = 0;
    amp_mesh_init(&m, NULL);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    ck_assert_int_eq(fx_implicit(&m, vee_f, NULL, amp_v3(-4, -7, -0.13), amp_v3(4, 7, 4.3), 0.25), AMP_OK);
    so.layer = 0.2;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, &err), AMP_OK);
    ck_assert_double_gt(amp_polyset_area(&sl.layers[0].polys), 0);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    ck_assert_int_eq(amp_contpath_layers(&sl, &o, &ps, &st, &err), AMP_OK);
    ck_assert_uint_eq(st.empty_layers, 0);
    ck_assert_uint_eq(st.dropped_islands, 0);
    ck_assert_uint_ge(st.thin_islands, 1);
    for (i = 0; i < ps.npaths; i++)
        first_layer_paths += fabs(amp_pathset_path_verts(&ps, i)[0].p.z - sl.layers[0].z_print) < 1e-9;
    ck_assert_uint_eq(first_layer_paths, 1);
    ck_assert_double_eq_tol(amp_pathset_path_verts(&ps, 0)[0].p.z, 0.2, 1e-9);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
}
END_TEST

/* Fraction of the points of the infill rings (the inset by 3r of every
 * island, computed here from the sections) within @p reach of a printed
 * segment at the layer's height: every 4th layer, points 0.05 mm apart. */
static double ring_cover(const amp_slices *sl, const amp_pathset *ps, double r, double reach)
{
    amp_polyset isl, ins;
    size_t li, k, q, i, j, total = 0, covered = 0;
    amp_polyset_init(&isl, NULL);
    amp_polyset_init(&ins, NULL);
    for (li = 0; li < sl->nlayers; li += 4) {
        const amp_layer *L = &sl->layers[li];
        for (k = 0; k < L->polys.nislands; k++) {
            ck_assert_int_eq(amp_polyset_island(&L->polys, k, &isl, NULL), AMP_OK);
            ck_assert_int_eq(amp_polyset_inset(&isl, 3 * r, 0, &ins, NULL), AMP_OK);
            for (q = 0; q < ins.nrings; q++) {
                const amp_vec2 *p = amp_polyset_ring(&ins, q);
                size_t n = ins.rings[q].n;
                for (j = 0; j < n; j++) {
                    amp_vec2 a = p[j], b = p[(j + 1) % n];
                    double len = hypot(b.x - a.x, b.y - a.y), t;
                    for (t = 0; t < len; t += 0.05) {
                        amp_vec3 x = amp_v3(a.x + (b.x - a.x) * t / len, a.y + (b.y - a.y) * t / len, 0);
                        double best = HUGE_VAL;
                        for (i = 0; i < ps->npaths && best > reach; i++) {
                            const amp_pvert *v = amp_pathset_path_verts(ps, i);
                            size_t e;
                            if (fabs(v[0].p.z - L->z_print) > 1e-9)
                                continue;
                            for (e = 0; e + 1 < ps->paths[i].n && best > reach; e++)
                                if (v[e].r > 0 && v[e + 1].r > 0)
                                    best = fmin(best, sqrt(amp_v3_seg_dist2(x, amp_v3(v[e].p.x, v[e].p.y, 0),
                                                                            amp_v3(v[e + 1].p.x, v[e + 1].p.y, 0),
                                                                            NULL)));
                        }
                        total++;
                        covered += best <= reach;
                    }
                }
            }
        }
    }
    amp_polyset_free(&isl);
    amp_polyset_free(&ins);
    return total ? (double)covered / (double)total : 0;
}

START_TEST(support_corners_cover_the_unprinted_stretches_of_the_infill_ring)
{
    /* step 6: with the corners every point of the rings of R̃ lies within r
     * of material (the ring's own patches, lattice ends, or a corner); the
     * same slicing without corners leaves stretches bare */
    amp_slices sl, sl2;
    amp_pathset a, b;
    amp_contpath_stats sa, sb;
    amp_contpath_opts o;
    double ca, cb;
    amp_slices_init(&sl, NULL);
    amp_slices_init(&sl2, NULL);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    /* step 6 is about the sparse lattice: solid regions take no corners */
    o.skin_bottom = o.skin_top = 0;
    layers_of(FX_PART_IDLER, 0.8, 0.2, 0, &sl, &a, &sa, &o);
    o.support_corners = 0;
    layers_of(FX_PART_IDLER, 0.8, 0.2, 0, &sl2, &b, &sb, &o);
    ck_assert_uint_gt(sa.support_corners, 100);
    ck_assert_uint_eq(sb.support_corners, 0);
    ck_assert_double_gt(sa.unprinted_length, 0);
    ca = ring_cover(&sl, &a, 0.225, 0.225 * 1.01);
    cb = ring_cover(&sl2, &b, 0.225, 0.225 * 1.01);
    ck_assert_msg(ca >= 0.99 && 1 - ca <= 0.5 * (1 - cb), "ring within r of material: %g with corners, %g without", ca, cb);
    /* on the sparse lattice alone about one corner in eight finds no room
     * (188 of 1,530 on the idler): the ring coverage above is what counts */
    ck_assert_uint_le(sa.corners_left_out, sa.support_corners / 8);
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_slices_free(&sl);
    amp_slices_free(&sl2);
}
END_TEST

/*
 * With skins (the default), the sparse core of a skin region lies one bead inside its band: its ring's bare
 * stretches have no perimeter within 3r, and the band's strips touch them (centre lines within 2r). They are
 * counted as touched, not as corners left out (on the twisted bridge 6,833 of 7,078 "left out" were these).
 */
START_TEST(core_rings_beside_skin_bands_are_touched_not_left_out)
{
    amp_slices sl;
    amp_pathset a;
    amp_contpath_stats sa;
    amp_contpath_opts o;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&a, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke;
    layers_of(FX_PART_TORUS, 0.8, 0.2, 0, &sl, &a, &sa, &o);
    ck_assert_uint_gt(sa.skin_bands, 0);
    ck_assert_uint_gt(sa.corners_touched, 0);
    ck_assert_msg(sa.corners_left_out <= sa.support_corners / 8, "%lu corners left out, %lu built, %lu touched",
                  (unsigned long)sa.corners_left_out, (unsigned long)sa.support_corners,
                  (unsigned long)sa.corners_touched);
    amp_pathset_free(&a);
    amp_slices_free(&sl);
}
END_TEST

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* Independent bead coverage of one layer: the section rasterised by
 * scanlines (pixel @p px), every printed segment at height z stamped as a
 * capsule of radius r; the fraction of the section's pixels under a bead. */
/* Is q a skin point of layer li: outside some section within T below or
 * above it (the part's first and last T count as outside)? Decided here
 * from the sections, independently of the builder. */
static int skin_point(const amp_slices *sl, const amp_polyindex *ix, size_t li, amp_vec2 q, double T)
{
    double z = sl->layers[li].z_print;
    size_t j;
    if (z - sl->layers[0].z_print < T - 1e-9 || sl->layers[sl->nlayers - 1].z_print - z < T - 1e-9)
        return 1;
    for (j = 0; j < sl->nlayers; j++)
        if (j != li && fabs(sl->layers[j].z_print - z) < T + 1e-9 && amp_polyindex_contains(&ix[j], q) != 1)
            return 1;
    return 0;
}

/* Fraction of the section's pixels (px mm) under a bead (within r of a
 * printed segment at height z); with @p sl, only of the skin pixels of
 * layer li (skin_point, thickness T), their count in *nskin. */
static double bead_coverage_of(const amp_polyset *sec, const amp_pathset *ps, double z, double r, double px,
                               const amp_slices *sl, const amp_polyindex *ix, size_t li, double T, size_t *nskin)
{
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, *xs;
    size_t i, k, nx, ny, in = 0, hit = 0;
    unsigned char *img;
    for (i = 0; i < sec->npts; i++) {
        x0 = fmin(x0, sec->pts[i].x);
        y0 = fmin(y0, sec->pts[i].y);
        x1 = fmax(x1, sec->pts[i].x);
        y1 = fmax(y1, sec->pts[i].y);
    }
    nx = (size_t)((x1 - x0) / px) + 1;
    ny = (size_t)((y1 - y0) / px) + 1;
    img = calloc(nx * ny, 1);
    xs = malloc((sec->npts + 1) * sizeof *xs);
    ck_assert(img && xs);
    /* 1: inside the section (even-odd spans of each row) */
    for (k = 0; k < ny; k++) {
        double y = y0 + (k + 0.5) * px;
        size_t nxs = 0, q, r2;
        for (r2 = 0; r2 < sec->nrings; r2++) {
            const amp_vec2 *p = amp_polyset_ring(sec, r2);
            size_t n = sec->rings[r2].n;
            for (q = 0; q < n; q++) {
                amp_vec2 a = p[q], b = p[(q + 1) % n];
                if ((a.y > y) != (b.y > y))
                    xs[nxs++] = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
            }
        }
        qsort(xs, nxs, sizeof *xs, cmp_dbl);
        for (q = 0; q + 1 < nxs; q += 2) {
            size_t c0 = (size_t)fmax(0, ceil((xs[q] - x0) / px - 0.5)), c1;
            for (c1 = c0; c1 < nx && x0 + (c1 + 0.5) * px < xs[q + 1]; c1++)
                img[k * nx + c1] = 1;
        }
    }
    /* 2: under a bead */
    for (i = 0; i < ps->npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(ps, i);
        if (fabs(v[0].p.z - z) > 1e-9)
            continue;
        for (k = 0; k + 1 < ps->paths[i].n; k++) {
            amp_vec3 a = amp_v3(v[k].p.x, v[k].p.y, 0), b = amp_v3(v[k + 1].p.x, v[k + 1].p.y, 0);
            long cx0, cx1, cy0, cy1, cx, cy;
            if (!(v[k].r > 0) || !(v[k + 1].r > 0))
                continue;
            cx0 = (long)floor((fmin(a.x, b.x) - r - x0) / px);
            cx1 = (long)ceil((fmax(a.x, b.x) + r - x0) / px);
            cy0 = (long)floor((fmin(a.y, b.y) - r - y0) / px);
            cy1 = (long)ceil((fmax(a.y, b.y) + r - y0) / px);
            for (cy = cy0 < 0 ? 0 : cy0; cy <= cy1 && cy < (long)ny; cy++)
                for (cx = cx0 < 0 ? 0 : cx0; cx <= cx1 && cx < (long)nx; cx++) {
                    amp_vec3 c = amp_v3(x0 + (cx + 0.5) * px, y0 + (cy + 0.5) * px, 0);
                    if (img[cy * nx + cx] == 1 && amp_v3_seg_dist2(c, a, b, NULL) <= r * r)
                        img[cy * nx + cx] = 2;
                }
        }
    }
    for (i = 0; i < nx * ny; i++) {
        if (img[i] && sl &&
            !skin_point(sl, ix, li, amp_v2(x0 + ((double)(i % nx) + 0.5) * px, y0 + ((double)(i / nx) + 0.5) * px), T))
            continue;

        in += img[i] != 0;
        hit += img[i] == 2;
    }
    if (nskin)
        *nskin = in;
    free(img);
    free(xs);
    return in ? (double)hit / (double)in : 0;
}

static double bead_coverage(const amp_polyset *sec, const amp_pathset *ps, double z, double r, double px)
{
    return bead_coverage_of(sec, ps, z, r, px, NULL, NULL, 0, 0, NULL);
}

/* between the last strip of a solid region and the perimeter a
 * sliver up to a bead wide stayed bare where the ring of R̃ runs parallel to
 * the strips and the patching leaves it unprinted (solid regions took no
 * corners). They now take corners where no strip runs within r of the
 * ring: every layer of the idler solid (skins thicker than the part), the
 * points of the infill rings within r of material, with and without. */
START_TEST(solid_regions_leave_no_sliver_bare_beside_their_strips)
{
    amp_slices sl, sl2;
    amp_pathset a, b;
    amp_contpath_stats sa, sb;
    amp_contpath_opts o;
    double ca, cb;
    amp_slices_init(&sl, NULL);
    amp_slices_init(&sl2, NULL);
    amp_pathset_init(&a, NULL);
    amp_pathset_init(&b, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    o.skin_bottom = o.skin_top = 10;
    layers_of(FX_PART_IDLER, 0.8, 0.2, 0, &sl, &a, &sa, &o);
    o.support_corners = 0;
    layers_of(FX_PART_IDLER, 0.8, 0.2, 0, &sl2, &b, &sb, &o);
    ck_assert_uint_eq(sa.skin_regions, sa.regions);
    ck_assert_uint_gt(sa.support_corners, 0);
    ck_assert_uint_eq(sa.island_strokes, sa.islands);
    ca = ring_cover(&sl, &a, 0.225, 0.225 * 1.01);
    cb = ring_cover(&sl2, &b, 0.225, 0.225 * 1.01);
    ck_assert_msg(ca >= 0.99 && 1 - ca <= 0.5 * (1 - cb), "ring within r of material: %g with corners, %g without", ca,
                  cb);
    amp_pathset_free(&a);
    amp_pathset_free(&b);
    amp_slices_free(&sl);
    amp_slices_free(&sl2);
}
END_TEST

/* skins only where needed. A region is solid only in a band along
 * its boundary that holds every uncovered point (and sparse one bead
 * further in), without polygon booleans. On the torus part (curved top and
 * bottom: the uncovered part of a layer is a ring along the section's
 * edge), measured independently: on every 3rd layer, the skin pixels
 * (outside some section within 0.8 mm, decided from the sections) are
 * >= 95 % under beads, while the layers' sparse middle is not solid; one
 * stroke per island, checks clean. */
START_TEST(skins_are_solid_only_where_a_layer_is_uncovered)
{
    amp_slices sl;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    amp_polyindex *ix;
    size_t li, i, banded = 0;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    layers_of(FX_PART_TORUS, 0.8, 0.2, 0, &sl, &ps, &st, &o);
    ck_assert_uint_gt(st.skin_bands, 0);
    ck_assert_uint_eq(st.island_strokes, st.islands);
    for (i = 0; i < ps.npaths; i++)
        ck_assert(amp_check_path_stroke(&ps, i, NULL, 0, NULL, NULL) == AMP_OK);
    ix = calloc(sl.nlayers, sizeof *ix);
    ck_assert(ix != NULL);
    for (li = 0; li < sl.nlayers; li++)
        ck_assert_int_eq(amp_polyindex_build(&ix[li], &sl.layers[li].polys, NULL), AMP_OK);
    for (li = 0; li < sl.nlayers; li += 3) {
        size_t nskin = 0, nall = 0;
        double cs = bead_coverage_of(&sl.layers[li].polys, &ps, sl.layers[li].z_print, 0.225, 0.05, &sl, ix, li, 0.8,
                                     &nskin);
        double ca = bead_coverage_of(&sl.layers[li].polys, &ps, sl.layers[li].z_print, 0.225, 0.05, NULL, NULL, 0, 0,
                                     &nall);
        if (nskin > 100)
            ck_assert_msg(cs >= 0.95, "layer %lu: %g of %lu skin pixels under beads", (unsigned long)li, cs,
                          (unsigned long)nskin);
        /* a layer with a skin ring and a sparse middle: not all of it solid */
        if (nskin > 100 && nskin < nall / 2 && ca < 0.85)
            banded++;
    }
    ck_assert_uint_gt(banded, 2);
    for (li = 0; li < sl.nlayers; li++)
        amp_polyindex_free(&ix[li]);
    free(ix);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
}
END_TEST

/* Area (mm^2) of the skin pixels of layer li (skin_point, thickness T) inside its section, pixel px. */
static double skin_area(const amp_slices *sl, const amp_polyindex *ix, size_t li, double T, double px)
{
    const amp_polyset *sec = &sl->layers[li].polys;
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, x, y;
    size_t i, n = 0;
    for (i = 0; i < sec->npts; i++) {
        x0 = fmin(x0, sec->pts[i].x);
        y0 = fmin(y0, sec->pts[i].y);
        x1 = fmax(x1, sec->pts[i].x);
        y1 = fmax(y1, sec->pts[i].y);
    }
    for (y = y0 + 0.5 * px; y < y1; y += px)
        for (x = x0 + 0.5 * px; x < x1; x += px)
            n += amp_polyindex_contains(&ix[li], amp_v2(x, y)) == 1 && skin_point(sl, ix, li, amp_v2(x, y), T);
    return (double)n * px * px;
}

/* The torus of the skin cost test: ring radius 40, tube 6 mm, on the plate, sliced at 0.2 mm. */
static void big_torus_layers(amp_slices *sl, amp_pathset *ps, amp_contpath_stats *st, const amp_contpath_opts *o)
{
    amp_mesh m;
    amp_slice_opts so;
    amp_error err;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_torus(&m, amp_v3(0, 0, 6), 40, 6, 240, 48), AMP_OK);
    so.layer = 0.2;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, sl, &err), AMP_OK);
    ck_assert_msg(amp_contpath_layers(sl, o, ps, st, &err) == AMP_OK, "%s", err.msg);
    amp_mesh_free(&m);
}

/* Skins cost the plastic of the uncovered points, not of a band a grid cell wide. A torus 92 mm across
 * and 12 mm high (tube radius 6) at 20 % infill: its steep flanks leave a rim a fraction of a millimetre
 * wide uncovered on most layers. The plastic the skins add over the sparse slice is measured against
 * the volume of the skin pixels (decided from the sections, independently of the builder): solid where
 * sparse was, the rim costs (1 - 0.2) of its volume, plus the band's margin and the beads along its
 * inner ring. A band as deep as a 16 x 16 grid of samples (its spacing, 5.8 mm here, added to the depth
 * found) cost 0.75 x; bands as deep as the sections' edges reach cost 0.44 x. */
START_TEST(skins_cost_the_plastic_of_the_uncovered_rim_not_of_a_grid_cell)
{
    amp_slices sl;
    amp_pathset ps, sparse;
    amp_contpath_stats st;
    amp_contpath_opts o;
    amp_polyindex *ix;
    double vskin = 0.0, extra;
    size_t li;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    amp_pathset_init(&sparse, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke;
    o.cell = 4 * o.radius / (1 - sqrt(1 - 0.2)); /* --infill 20 */
    big_torus_layers(&sl, &ps, &st, &o);
    ck_assert_uint_eq(st.island_strokes, st.islands);
    ck_assert_uint_eq(st.band_retries, 0);
    amp_slices_free(&sl);
    amp_slices_init(&sl, NULL);
    o.skin_bottom = o.skin_top = 0;
    big_torus_layers(&sl, &sparse, &st, &o);
    ix = calloc(sl.nlayers, sizeof *ix);
    ck_assert(ix != NULL);
    for (li = 0; li < sl.nlayers; li++)
        ck_assert_int_eq(amp_polyindex_build(&ix[li], &sl.layers[li].polys, NULL), AMP_OK);
    for (li = 0; li < sl.nlayers; li++)
        vskin += skin_area(&sl, ix, li, 0.8, 0.1) * 0.2;
    extra = amp_pathset_volume(&ps, AMP_ROLE_OBJECT) - amp_pathset_volume(&sparse, AMP_ROLE_OBJECT);
    ck_assert_double_gt(vskin, 1000.0);
    /* and no less than needed: the skin pixels under beads */
    for (li = 0; li < sl.nlayers; li += 5) {
        size_t nskin = 0;
        double cs = bead_coverage_of(&sl.layers[li].polys, &ps, sl.layers[li].z_print, 0.225, 0.05, &sl, ix, li, 0.8,
                                     &nskin);
        /* at z 8.2 the skin is only the outermost rim, 0.25 mm wide: the corners' teeth, whose bases the
         * perimeter skips, left 5.5 % of it bare while they were 2r wide (Fig. 5c), 1.1 % at r */
        if (nskin > 100)
            ck_assert_msg(cs >= 0.98, "layer %lu: %g of %lu skin pixels under beads", (unsigned long)li, cs,
                          (unsigned long)nskin);
    }
    ck_assert_msg(extra <= 0.6 * vskin, "skins add %.1f mm3 for %.1f mm3 of skin pixels (%.2f x)", extra, vskin,
                  extra / vskin);
    for (li = 0; li < sl.nlayers; li++)
        amp_polyindex_free(&ix[li]);
    free(ix);
    amp_pathset_free(&ps);
    amp_pathset_free(&sparse);
    amp_slices_free(&sl);
}
END_TEST

/* A loop the splices cannot join that fits in 2r (a lattice piece cutting a corner of the region, 0.3 mm:
 * CGAL's `eight` had a layer of 2 islands and 3 strokes) is dropped as a speck, so the island keeps one stroke;
 * a straggler larger than that stays. */
START_TEST(a_tiny_loop_the_splices_cannot_join_is_a_speck_not_a_second_stroke)
{
    static const double size[2] = {0.3, 2.0};
    int t;
    for (t = 0; t < 2; t++) {
        amp_pathset in, out;
        amp_polyset walls;
        amp_vec2 w[4] = {{-1, -1}, {11, -1}, {11, 11}, {-1, 11}};
        size_t nout = 0, nspeck = 0;
        double d = size[t];
        amp_pathset_init(&in, NULL);
        amp_pathset_init(&out, NULL);
        amp_polyset_init(&walls, NULL);
        ck_assert_int_eq(amp_polyset_add(&walls, w, 4, NULL), AMP_OK);
        /* the perimeter loop, closed (last = first) */
        amp_pathset_begin(&in, AMP_ROLE_OBJECT, NULL);
        amp_pathset_push(&in, amp_v3(0, 0, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(10, 0, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(10, 10, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(0, 10, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(0, 0, 0.2), 0.225, NULL);
        /* a thin triangle loop in the middle, far from the perimeter (no splice reaches it) */
        amp_pathset_begin(&in, AMP_ROLE_OBJECT, NULL);
        amp_pathset_push(&in, amp_v3(5, 5, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(5 + 0.04, 5 + d, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(5 - 0.04, 5 + d, 0.2), 0.225, NULL);
        amp_pathset_push(&in, amp_v3(5, 5, 0.2), 0.225, NULL);
        ck_assert_int_eq(amp_cp_join_loops(&in, 0, &walls, 0.225, 0.2, &out, &nout, &nspeck, NULL), AMP_OK);
        ck_assert_uint_eq(nout, t == 0 ? 1 : 2);
        ck_assert_uint_eq(nspeck, t == 0 ? 1 : 0);
        amp_pathset_free(&in);
        amp_pathset_free(&out);
        amp_polyset_free(&walls);
    }
}
END_TEST

/* The stretch of a loop a splice leaves out is the shorter one by length, not by segment count: a skin band's
 * loop of two 32 mm strands (7 segments) spliced at its end, where 4 short segments round it off, lost both
 * strands to the splice (the 3 segments of the long way were "fewer") and left a 1 mm strip of a top skin bare
 * (CGAL's fandisk, layer 144: the loop and the perimeter with its corners, as the slicer made them). */
START_TEST(a_splice_leaves_out_the_short_end_of_a_long_loop_with_few_segments)
{
    static const double perim[][2] = {
        {31.166, 9.7315},  {31.9004, 9.7532}, {32.7162, 9.7518}, {32.7841, 9.9172}, {32.7972, 9.9490},
        {32.8013, 9.9584}, {32.8204, 9.9992}, {33.1300, 10.6550}, {32.7709, 10.9484}, {33.2257, 10.8575},
        {33.2903, 10.9944}, {33.2944, 11.0026}, {33.5755, 11.5402}, {33.2289, 11.8484}, {33.6798, 11.7396},
        {33.7109, 11.7991}, {33.8360, 12.0366}, {33.8411, 12.0458}, {34.0630, 12.4233}, {33.7322, 12.7483},
        {34.1771, 12.6172}, {34.2378, 12.7205}, {40.0, 12.7205}, {40.0, 9.7315}, {31.166, 9.7315}};
    static const double strands[][2] = {{32.8772, 11.1734}, {0.675, 11.1734},   {0.675, 11.6234},
                                        {33.1112, 11.6234}, {32.8956, 11.2111}, {32.8893, 11.1989},
                                        {32.8834, 11.1865}, {32.8772, 11.1734}};
    const double r = 0.225;
    amp_pathset in, out;
    amp_polyset walls;
    amp_vec2 w[4] = {{0.0, 9.4}, {41.0, 9.4}, {41.0, 14.0}, {0.0, 14.0}};
    size_t nout = 0, nspeck = 0, i, k;
    double len_in, len_out, probe[2] = {8.0, 11.1734}, best = HUGE_VAL;
    amp_pathset_init(&in, NULL);
    amp_pathset_init(&out, NULL);
    amp_polyset_init(&walls, NULL);
    ck_assert_int_eq(amp_polyset_add(&walls, w, 4, NULL), AMP_OK);
    amp_pathset_begin(&in, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k < sizeof perim / sizeof perim[0]; k++)
        amp_pathset_push(&in, amp_v3(perim[k][0], perim[k][1], 29.0), r, NULL);
    amp_pathset_begin(&in, AMP_ROLE_OBJECT, NULL);
    for (k = 0; k < sizeof strands / sizeof strands[0]; k++)
        amp_pathset_push(&in, amp_v3(strands[k][0], strands[k][1], 29.0), r, NULL);
    len_in = amp_pathset_length(&in, AMP_ROLE_OBJECT);
    ck_assert_int_eq(amp_cp_join_loops(&in, 0, &walls, r, 0.2, &out, &nout, &nspeck, NULL), AMP_OK);
    ck_assert_uint_eq(nout, 1); /* the case is exercised: the two loops were spliced into one */
    len_out = amp_pathset_length(&out, AMP_ROLE_OBJECT);
    /* a splice leaves out about 2r of each loop and adds two connectors: the strands' 64 mm stay */
    ck_assert_msg(len_out > len_in - 8 * r, "joined %.3f mm of %.3f mm", len_out, len_in);
    for (i = 0; i < out.npaths; i++) {
        const amp_pvert *v = amp_pathset_path_verts(&out, i);
        for (k = 0; k + 1 < out.paths[i].n; k++)
            best = fmin(best, amp_v3_seg_dist2(amp_v3(probe[0], probe[1], 29.0), v[k].p, v[k + 1].p, NULL));
    }
    ck_assert_msg(sqrt(best) < 1e-9, "the lower strand at x 8 is %.3f mm from the stroke", sqrt(best));
    amp_pathset_free(&in);
    amp_pathset_free(&out);
    amp_polyset_free(&walls);
}
END_TEST

/* Step 6 out of memory at every allocation in turn: AMP_ERR_NOMEM until the budget suffices, and every block the
 * corners allocated freed exactly once (the tooth array grown and then the legs' growth failing left the
 * grown array unowned and the old one freed twice: a black-box allocation sweep found it). */
START_TEST(support_corners_out_of_memory_frees_every_block_once)
{
    const double r = 0.225;
    long budget, need = -1;
    size_t corners = 0;
    for (budget = 0; budget < 4000 && need < 0; budget++) {
        fx_failalloc fa;
        amp_pathset ps, bare;
        amp_contpath_stats st;
        amp_status rc;
        size_t k;
        fx_failalloc_init(&fa, 1L << 30);
        amp_pathset_init(&ps, &fa.a);
        amp_pathset_init(&bare, NULL);
        memset(&st, 0, sizeof st);
        /* the perimeter loop of a 10 mm square at r, and its ring R̃ at 3r bare along the bottom and right */
        ck_assert_int_eq(amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL), AMP_OK);
        amp_pathset_push(&ps, amp_v3(r, r, 0.2), r, NULL);
        amp_pathset_push(&ps, amp_v3(10 - r, r, 0.2), r, NULL);
        amp_pathset_push(&ps, amp_v3(10 - r, 10 - r, 0.2), r, NULL);
        amp_pathset_push(&ps, amp_v3(r, 10 - r, 0.2), r, NULL);
        amp_pathset_push(&ps, amp_v3(r, r, 0.2), r, NULL);
        amp_pathset_begin(&bare, AMP_ROLE_SUPPORT, NULL);
        for (k = 0; k <= 40; k++)
            amp_pathset_push(&bare, amp_v3(3 * r + (10 - 6 * r) * (double)k / 40, 3 * r, 0.2), 0, NULL);
        amp_pathset_push(&bare, amp_v3(10 - 3 * r, 5, 0.2), 0, NULL);
        fa.count = 0;
        fa.budget = budget;
        rc = amp_cp_support_corners(&ps, 1, &bare, r, 0.0, &st, NULL);
        fa.budget = 1L << 30;
        if (rc == AMP_OK) {
            need = budget;
            corners = st.support_corners;
        } else
            ck_assert_int_eq(rc, AMP_ERR_NOMEM);
        amp_pathset_free(&ps);
        amp_pathset_free(&bare);
        ck_assert_msg(fa.live == 0, "budget %ld: %ld blocks left", budget, fa.live);
    }
    ck_assert_msg(need > 0, "the corners never succeeded");
    /* the case is exercised: enough corners that their arrays grew several times */
    ck_assert_uint_gt(corners, 20);
}
END_TEST

/* A verifier out of memory is an error of the slice, not a rejected stroke: the island is not made again (the
 * tool would print paths that differ from the unfailed run's, with exit 0). */
static amp_status verifier_out_of_memory(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                         struct amp_stroke_report *rep, amp_error *err)
{
    (void)ps, (void)i, (void)region, (void)tol, (void)rep;
    return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
}

/* The twisted bridge at 0.5 mm layers made into strokes with verifier @p v, the output allocating with @p al
 * (a caller's allocator: the islands are made on the calling thread, in order); every object freed. */
static amp_status bridge_strokes_verified_by(amp_contpath_verify_fn v, const amp_allocator *al, amp_contpath_stats *st,
                                             amp_error *e)
{
    amp_mesh m;
    amp_slices sl;
    amp_slice_opts so = {0.5, 0};
    amp_contpath_opts o;
    amp_pathset ps;
    amp_status rc;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(amp_mesh_model("twisted-bridge", 1.0, &m, NULL), AMP_OK);
    amp_slices_init(&sl, NULL);
    ck_assert_int_eq(amp_slice_mesh(&m, &so, &sl, NULL), AMP_OK);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = v;
    amp_pathset_init(&ps, al);
    memset(st, 0, sizeof *st);
    rc = amp_contpath_layers(&sl, &o, &ps, st, e);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_mesh_free(&m);
    return rc;
}

START_TEST(a_verifier_out_of_memory_stops_the_slice_with_that_error)
{
    amp_contpath_stats st;
    amp_error e;
    amp_error_clear(&e);
    ck_assert_int_eq(bridge_strokes_verified_by(verifier_out_of_memory, NULL, &st, &e), AMP_ERR_NOMEM);
    ck_assert_uint_eq(st.shift_retries + st.band_retries, 0);
    ck_assert_msg(strstr(e.msg, "out of memory") != NULL, "%s", e.msg);
}
END_TEST

/* A verifier that rejects its first path and then runs out of memory once: the retry that follows the rejection
 * must stop at the failure too (it went on with the next try, which passed: exit 0 with other paths). */
static int reject_then_oom_calls;
static amp_status reject_then_out_of_memory(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                            struct amp_stroke_report *rep, amp_error *err)
{
    (void)ps, (void)i, (void)region, (void)tol, (void)rep;
    reject_then_oom_calls++;
    if (reject_then_oom_calls == 1)
        return AMP_ERR_GEOMETRY;
    if (reject_then_oom_calls == 2)
        return amp_fail(err, AMP_ERR_NOMEM, 0, "out of memory checking a stroke");
    return AMP_OK;
}

START_TEST(a_verifier_out_of_memory_in_a_retry_stops_the_slice_too)
{
    amp_contpath_stats st;
    fx_failalloc fa; /* a caller's allocator: the islands are made on this thread, in order */
    fx_failalloc_init(&fa, 1L << 40);
    reject_then_oom_calls = 0;
    /* NULL err: an island's error is not written through it */
    ck_assert_int_eq(bridge_strokes_verified_by(reject_then_out_of_memory, &fa.a, &st, NULL), AMP_ERR_NOMEM);
    ck_assert_int_ge(reject_then_oom_calls, 2); /* the islands computed beside it are verified too */
}
END_TEST

static size_t verifier_calls;

/* A verifier that rejects every path (counts its calls). */
static amp_status reject_every_path(const amp_pathset *ps, size_t i, const amp_polyset *region, double tol,
                                    struct amp_stroke_report *rep, amp_error *err)
{
    (void)ps, (void)i, (void)region, (void)tol, (void)rep, (void)err;
    verifier_calls++;
    return AMP_ERR_GEOMETRY;
}

/* The skin bands' safety net is the caller's: without a verifier
 * (verify_stroke NULL, the default) no island is printed again; with one
 * that rejects every path, every island printed with bands is printed again
 * with its skin regions whole (no bands are left, band_retries counts them),
 * and the verifier was asked about each of its paths. */
START_TEST(the_band_retry_asks_the_callers_verifier)
{
    amp_slices sl;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    amp_contpath_opts_default(&o, 0.225);
    ck_assert(o.verify_stroke == NULL);
    layers_of(FX_PART_TORUS, 0.8, 0.2, 0, &sl, &ps, &st, &o);
    ck_assert_uint_gt(st.skin_bands, 0);
    ck_assert_uint_eq(st.band_retries, 0);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    o.verify_stroke = reject_every_path;
    verifier_calls = 0;
    layers_of(FX_PART_TORUS, 0.8, 0.2, 0, &sl, &ps, &st, &o);
    ck_assert_uint_eq(st.skin_bands, 0);
    ck_assert_uint_gt(st.band_retries, 0);
    ck_assert_uint_ge(verifier_calls, st.band_retries);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
}
END_TEST

/* The library's continuous slice of the STL file @p stl (the mesh as the tool reads it: the float rounding
 * of its vertices decides the cases of the sweep) at layers @p h, beads of radius @p r, with the tool's
 * verifier, into @p sl (initialised here) and @p ps. */
static void slice_stl(const char *stl, double h, double r, amp_slices *sl, amp_pathset *ps, amp_contpath_stats *st)
{
    amp_mesh m;
    amp_slice_opts so;
    amp_contpath_opts o;
    amp_error err;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(amp_mesh_read_stl_file(&m, stl, &err), AMP_OK);
    amp_slices_init(sl, NULL);
    so.layer = h;
    so.first_layer = 0;
    ck_assert_int_eq(amp_slice_mesh(&m, &so, sl, &err), AMP_OK);
    amp_contpath_opts_default(&o, r);
    o.verify_stroke = amp_check_path_stroke;
    ck_assert_msg(amp_contpath_layers(sl, &o, ps, st, &err) == AMP_OK, "%s", err.msg);
    amp_mesh_free(&m);
}

/* Paths that fail the stroke check (crossings, edges twice, points outside) in a slice of part @p p meshed
 * at @p step, layers @p h, beads of radius @p r, as the tool makes it. */
static size_t failed_strokes(fx_part p, double step, double h, double r, size_t *shifts)
{
    const char *stl = fx_tmp("split.stl");
    amp_mesh m;
    amp_error err;
    amp_slices sl;
    amp_pathset ps;
    amp_contpath_stats st;
    size_t i, bad = 0;
    amp_pathset_init(&ps, NULL);
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, p, step), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    amp_mesh_free(&m);
    slice_stl(stl, h, r, &sl, &ps, &st);
    remove(stl);
    for (i = 0; i < ps.npaths; i++)
        bad += amp_check_path_stroke(&ps, i, NULL, 0, NULL, NULL) != AMP_OK;
    *shifts = st.shift_retries;
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
    return bad;
}

/* Two offsets at the edge of a split, found by a sweep of the test parts (624 runs) where the tool said
 * "a bug, please report it" (exit 1): the torus meshed at 0.65 mm, 0.15 mm layers, r 0.25, whose first
 * layer has a sliver whose inset keeps a lobe of 5e-5 mm^2 pinched off at a vertex the ring passes twice
 * (the inset now cuts such lobes out), and the bunny meshed at 1.2 mm, 0.2 mm layers, r 0.2, whose ear at
 * z 26.2 splits at a neck: the perimeter's offset, bisected to the largest that keeps the island in one
 * piece, left a neck a hair wide whose sides crossed at the micrometre scale (the offset now backs off by
 * two brackets). And a third, the torus meshed at 1.3 mm, 0.2 mm layers, r 0.2, whose region's ring runs
 * within 0.001 mm of a lattice line at z 3.4, where a patch edge crossed the ring: the verifier rejects
 * that island, which is made again with its infill region moved in by r/20 (one shift retry; without it
 * the path fails). Every path passes the stroke check; the other two need no shift. */
START_TEST(offsets_at_the_edge_of_a_split_print_without_crossing)
{
    size_t shifts;
    ck_assert_uint_eq(failed_strokes(FX_PART_TORUS, 0.65, 0.15, 0.25, &shifts), 0);
    ck_assert_uint_eq(shifts, 0);
    ck_assert_uint_eq(failed_strokes(FX_PART_BUNNY, 1.2, 0.2, 0.2, &shifts), 0);
    ck_assert_uint_eq(shifts, 0);
    ck_assert_uint_eq(failed_strokes(FX_PART_TORUS, 1.3, 0.2, 0.2, &shifts), 0);
    ck_assert_uint_eq(shifts, 1);
}
END_TEST

START_TEST(a_band_that_fails_the_final_check_makes_the_tool_slice_again_with_the_verifier)
{
    /* the one case of 624 sweep runs (torus, idler, screw and bunny at 13 mesh steps, 4 layer heights, 3
     * radii) where a skin band's rings meet the core's: the bunny meshed at 0.45 mm, 0.25 mm layers, r 0.2
     * (with the bands a grid cell deep before stop 30: the bunny at 0.95 mm, 0.3 mm layers). The tool first
     * slices without the per-island verifier (its final check is the safety net); the check fails on that island, so the tool slices again with the verifier, which makes
     * the island with its skin regions whole: exit 0, one retry, every path clean, and the paths are those
     * the library makes with the verifier from the start */
    amp_mesh m;
    amp_error err;
    amp_slices sl;
    amp_pathset lib, cli;
    amp_contpath_stats st;
    char args[768], out[4096];
    const char *stl = fx_tmp("bandbunny.stl"), *amp = fx_tmp("bandbunny.amp");
    size_t i;
    amp_mesh_init(&m, NULL);
    ck_assert_int_eq(fx_part_mesh(&m, FX_PART_BUNNY, 0.45), AMP_OK);
    ck_assert_int_eq(amp_mesh_write_stl_file(&m, stl, 1, &err), AMP_OK);
    snprintf(args, sizeof args, "slice %s --layer 0.25 --radius 0.2 --continuous -o %s --json", stl, amp);
    ck_assert_int_eq(fx_run_tool(args, out, sizeof out), 0);
    ck_assert_msg(strstr(out, "\"band_retries\":1,") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"crossings\":0,\"repeated_edges\":0") != NULL, "%s", out);
    ck_assert_msg(strstr(out, "\"failed_paths\":0") != NULL, "%s", out);
    /* the library with the verifier, on the mesh as the tool read it */
    amp_mesh_free(&m);
    amp_pathset_init(&lib, NULL);
    slice_stl(stl, 0.25, 0.2, &sl, &lib, &st);
    ck_assert_uint_eq(st.band_retries, 1);
    amp_pathset_init(&cli, NULL);
    ck_assert_int_eq(amp_pathset_read_file(&cli, amp, &err), AMP_OK);
    ck_assert_uint_eq(cli.npaths, lib.npaths);
    ck_assert_uint_eq(cli.nverts, lib.nverts);
    for (i = 0; i < lib.nverts; i++) /* the file holds 10 significant digits, the library rounds to them */
        ck_assert(cli.verts[i].p.x == lib.verts[i].p.x && cli.verts[i].p.y == lib.verts[i].p.y);
    amp_pathset_free(&lib);
    amp_pathset_free(&cli);
    amp_slices_free(&sl);
    remove(stl);
    remove(amp);
}
END_TEST

START_TEST(skin_layers_are_covered_by_beads_and_sparse_layers_are_not)
{
    /* the idler's first and last layers are skins: >= 95 % of the section
     * under beads (measured here by rasterising); a middle layer keeps the
     * sparse lattice */
    amp_slices sl;
    amp_pathset ps;
    amp_contpath_stats st;
    amp_contpath_opts o;
    double c0, c1, cm;
    size_t last;
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
    layers_of(FX_PART_IDLER, 0.7, 0.2, 0, &sl, &ps, &st, &o);
    last = sl.nlayers - 1;
    ck_assert_uint_gt(st.skin_regions, 0);
    ck_assert_uint_eq(st.island_strokes, st.islands);
    c0 = bead_coverage(&sl.layers[0].polys, &ps, sl.layers[0].z_print, 0.225, 0.04);
    c1 = bead_coverage(&sl.layers[last].polys, &ps, sl.layers[last].z_print, 0.225, 0.04);
    cm = bead_coverage(&sl.layers[last / 2].polys, &ps, sl.layers[last / 2].z_print, 0.225, 0.04);
    ck_assert_msg(c0 >= 0.95 && c1 >= 0.95 && cm < 0.8, "bottom %g, top %g, middle %g", c0, c1, cm);
    amp_pathset_free(&ps);
    amp_slices_free(&sl);
}
END_TEST

START_TEST(of_the_two_pairings_of_a_ring_the_longer_is_printed)
{
    /* step 5, direct: one lattice edge crosses a 10 x 10 square region at
     * height y0; its two free ends on the ring can be joined by the ring
     * path below it (length 2 y0 + 10) or above it (2 (10 - y0) + 10). The
     * paper prints the longer: the stroke must reach the far side and not
     * the near one, whichever side is far. */
    static const double y0s[] = {1.0, 9.0};
    size_t t;
    for (t = 0; t < 2; t++) {
        amp_cx2 k;
        amp_polyset R;
        amp_pathset ps;
        amp_contpath_opts o;
        amp_contpath_stats st;
        amp_error err;
        amp_vec2 sq[4] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
        uint32_t a, b;
        size_t i;
        double ymin = HUGE_VAL, ymax = -HUGE_VAL;
        amp_cx2_init(&k, NULL);
        amp_polyset_init(&R, NULL);
        amp_pathset_init(&ps, NULL);
        memset(&st, 0, sizeof st);
        ck_assert_int_eq(amp_cx2_add_vertex(&k, amp_v2(-3, y0s[t]), &a, NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_add_vertex(&k, amp_v2(13, y0s[t] + 0.01), &b, NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_add_edge(&k, a, b, NULL), AMP_OK);
        ck_assert_int_eq(amp_cx2_build(&k, NULL), AMP_OK);
        ck_assert_int_eq(amp_polyset_add(&R, sq, 4, NULL), AMP_OK);
        ck_assert_int_eq(amp_polyset_organize(&R, NULL), AMP_OK);
        amp_contpath_opts_default(&o, 0.2);
        o.verify_stroke = amp_check_path_stroke; /* as the tool: the skin bands' safety net */
        ck_assert_msg(amp_contpath_region(&k, &R, 1.0, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
        ck_assert_uint_eq(st.free_ends, 2);
        ck_assert_uint_eq(ps.npaths, 1);
        for (i = 0; i < ps.paths[0].n; i++) {
            ymin = fmin(ymin, amp_pathset_path_verts(&ps, 0)[i].p.y);
            ymax = fmax(ymax, amp_pathset_path_verts(&ps, 0)[i].p.y);
        }
        if (y0s[t] < 5)
            ck_assert_msg(ymax == 10 && ymin >= y0s[t], "y0 %g: stroke spans y %g..%g", y0s[t], ymin, ymax);
        else
            ck_assert_msg(ymin == 0 && ymax <= y0s[t] + 0.01, "y0 %g: stroke spans y %g..%g", y0s[t], ymin, ymax);
        ck_assert_double_eq_tol(st.infill_length, 10 + 2 * (y0s[t] < 5 ? 10 - y0s[t] : y0s[t]) + 10.01, 0.02);
        amp_cx2_free(&k);
        amp_polyset_free(&R);
        amp_pathset_free(&ps);
    }
}
END_TEST

/* with --no-join (or --no-perimeter) the components of a region are
 * joined by Fig. 6's doubled ring paths, printed once and run back as a
 * pseudo edge. On the helix at 0.3 mm a ring vertex lies within 1 µm of a
 * free end; the layer code merged it on one copy and kept it on the other,
 * so the two copies interleaved at the free end: 30 crossings, exit 1. */
START_TEST(fig6_joins_stay_crossing_free_when_ring_vertices_crowd_a_free_end)
{
    static const char *const modes[] = {"--no-join", "--no-perimeter", "--no-join --pseudo"};
    char args[1024], out[8192];
    const char *stl = fx_tmp("helix_j.stl"), *amp = fx_tmp("helix_j.amp");
    size_t k;
    snprintf(args, sizeof args, "model helix -o %s", stl);
    ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
    for (k = 0; k < 3; k++) {
        snprintf(args, sizeof args, "slice %s --layer 0.3 --continuous %s -o %s --json", stl, modes[k], amp);
        ck_assert_msg(fx_run_tool(args, out, sizeof out) == 0, "%s: %s", modes[k], out);
        ck_assert_msg(strstr(out, "\"crossings\":0,\"repeated_edges\":0,\"outside\":0,\"failed_paths\":0") != NULL,
                      "%s: %s", modes[k], out);
        /* the joins are there: the case is exercised, not avoided */
        ck_assert_msg(strstr(out, "\"joins\":0,") == NULL, "%s: %s", modes[k], out);
        snprintf(args, sizeof args, "check %s --mesh %s --layer 0.3 --json", amp, stl);
        ck_assert_msg(fx_run_tool(args, out, sizeof out) == 0, "%s: %s", modes[k], out);
    }
    remove(stl);
    remove(amp);
}
END_TEST

/* an island whose inset by r splits at a neck narrower than a bead
 * (the twisted bridge at 0.2 mm: a 6 mm long bridge 0.30-0.45 mm wide joins
 * two lobes with infill) kept one stroke per lobe and left the neck bare
 * (197 starts for 196 islands). Its perimeter now runs at the largest offset
 * that holds it together, up one side of the neck and down the other.
 * Counted from the G-code on every layer of the built-in meshes. */
START_TEST(a_neck_narrower_than_a_bead_joins_its_lobes_in_one_stroke)
{
    static const char *const names[] = {"twisted-bridge", "crocodile-like", "helix"};
    static const double layers[] = {0.2, 0.3, 0.3};
    static char out[1 << 14];
    char args[1024];
    size_t k;
    for (k = 0; k < 3; k++) {
        char stl[400], nm[64];
        snprintf(nm, sizeof nm, "bi_%s.stl", names[k]);
        snprintf(stl, sizeof stl, "%s", fx_tmp(nm));
        snprintf(args, sizeof args, "model %s -o %s", names[k], stl);
        ck_assert_int_eq(fx_run_tool(args, NULL, 0), 0);
        stl_one_start_per_island(stl, names[k], layers[k], out, sizeof out);
        /* the case is exercised: the bridge and the crocodile have such necks */
        if (k < 2)
            ck_assert_msg(strstr(out, "\"neck_islands\":0,") == NULL, "%s: %s", names[k], out);
        remove(stl);
    }
}
END_TEST

START_TEST(a_perimeter_that_touches_itself_is_made_again_nearer_the_boundary)
{
    /* OpenSCAD's example013 cut at 10.45 mm (0.1 mm layers): a V notch whose tip lies exactly 2r = 0.45 mm
     * from the opposite wall. The inset by r touches itself there along one tangent step of the tip's arc,
     * and the perimeter loop ran that stretch both ways: an edge printed twice, the slice failed (exit 1).
     * Moving the infill region does not help; the perimeter r/16 nearer the boundary does */
    static const double xy[11][2] = {{20.225, -0.45000000000000284}, {20.0, 0.0}, {20.225, 0.45000000000000284},
                                     {29.775, 19.549999999999997}, {20.225, 19.549999999999997},
                                     {19.549999999999997, 19.549999999999997}, {19.549999999999997, 0.45000000000000284},
                                     {19.549999999999997, -0.45000000000000284},
                                     {19.549999999999997, -19.549999999999997}, {20.225, -19.549999999999997},
                                     {29.775, -19.549999999999997}};
    amp_slices sl;
    amp_layer L;
    amp_vec2 p[11];
    amp_contpath_opts o;
    amp_contpath_stats st;
    amp_pathset ps;
    amp_error err;
    size_t i;
    for (i = 0; i < 11; i++)
        p[i] = amp_v2(xy[i][0], xy[i][1]);
    amp_slices_init(&sl, NULL);
    amp_pathset_init(&ps, NULL);
    memset(&L, 0, sizeof L);
    amp_polyset_init(&L.polys, NULL);
    L.z_cut = 10.45;
    L.z_print = 10.5;
    ck_assert_int_eq(amp_polyset_add(&L.polys, p, 11, &err), AMP_OK);
    ck_assert_int_eq(amp_polyset_organize(&L.polys, &err), AMP_OK);
    sl.layers = &L;
    sl.nlayers = 1;
    amp_contpath_opts_default(&o, 0.225);
    o.verify_stroke = amp_check_path_stroke;
    ck_assert_msg(amp_contpath_layers(&sl, &o, &ps, &st, &err) == AMP_OK, "%s", err.msg);
    ck_assert_uint_eq(ps.npaths, 1);
    ck_assert_uint_eq(st.shift_retries, 1);
    for (i = 0; i < ps.npaths; i++) {
        amp_stroke_report rep;
        ck_assert_int_eq(amp_check_path_stroke(&ps, i, &L.polys, 1e-6, &rep, NULL), AMP_OK);
        ck_assert_uint_eq(rep.repeated_edges, 0);
    }
    amp_pathset_free(&ps);
    amp_polyset_free(&L.polys);
}
END_TEST

static Suite *contpath_suite(void)
{
    Suite *s = suite_create("contpath");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, torus_sections_get_one_crossing_free_stroke);
    tcase_add_test(tc, plate_with_holes_islands_and_a_thin_neck_gets_one_stroke_per_region);
    tcase_add_test(tc, perforated_plate_with_many_holes_gets_one_stroke);
    tcase_add_test(tc, perforated_plate_hex_lattice_joins_its_components_into_one_stroke);
    tcase_add_test(tc, thin_boundary_cells_become_pseudo_edges_so_beads_do_not_collide);
    tcase_add_test(tc, all_layers_of_a_sphere_and_torus_pair);
    tcase_add_test(tc, built_in_models_get_one_crossing_free_stroke_per_island);
    tcase_add_test(tc, stroke_checker_rejects_crossings_repeats_and_escapes);
    tcase_add_test(tc, stroke_checker_counts_every_crossing_of_a_long_stroke_once);
    tcase_add_test(tc, cli_continuous_gives_one_stroke_per_island_and_check_agrees);
    tcase_add_test(tc, printer_profile_sets_the_bead_width_of_a_continuous_slice);
    tcase_add_test(tc, torus_and_idler_get_one_extrusion_start_per_island_counted_in_the_gcode);
    tcase_add_test(tc, screw_bunny_and_open_mesh_get_one_extrusion_start_per_island_counted_in_the_gcode);
    tcase_add_test(tc, paths_carry_their_layer_bead_height_and_start_where_the_nozzle_is);
    tcase_add_test(tc, cycle_tree_and_merging_trace_the_same_edges_once_without_crossing);
    tcase_add_test(tc, a_sliver_first_layer_is_printed_on_the_bed);
    tcase_add_test(tc, support_corners_cover_the_unprinted_stretches_of_the_infill_ring);
    tcase_add_test(tc, core_rings_beside_skin_bands_are_touched_not_left_out);
    tcase_add_test(tc, skin_layers_are_covered_by_beads_and_sparse_layers_are_not);
    tcase_add_test(tc, of_the_two_pairings_of_a_ring_the_longer_is_printed);
    tcase_add_test(tc, fig6_joins_stay_crossing_free_when_ring_vertices_crowd_a_free_end);
    tcase_add_test(tc, a_neck_narrower_than_a_bead_joins_its_lobes_in_one_stroke);
    tcase_add_test(tc, solid_regions_leave_no_sliver_bare_beside_their_strips);
    tcase_add_test(tc, skins_are_solid_only_where_a_layer_is_uncovered);
    tcase_add_test(tc, skins_cost_the_plastic_of_the_uncovered_rim_not_of_a_grid_cell);
    tcase_add_test(tc, a_tiny_loop_the_splices_cannot_join_is_a_speck_not_a_second_stroke);
    tcase_add_test(tc, a_splice_leaves_out_the_short_end_of_a_long_loop_with_few_segments);
    tcase_add_test(tc, support_corners_out_of_memory_frees_every_block_once);
    tcase_add_test(tc, a_verifier_out_of_memory_stops_the_slice_with_that_error);
    tcase_add_test(tc, a_verifier_out_of_memory_in_a_retry_stops_the_slice_too);
    tcase_add_test(tc, offsets_at_the_edge_of_a_split_print_without_crossing);
    tcase_add_test(tc, the_band_retry_asks_the_callers_verifier);
    tcase_add_test(tc, islands_made_on_many_threads_equal_those_made_on_one);
    tcase_add_test(tc, beads_that_overlap_are_narrowed_to_the_volume_of_their_slab);
    tcase_add_test(tc, a_band_that_fails_the_final_check_makes_the_tool_slice_again_with_the_verifier);
    tcase_add_test(tc, a_perimeter_that_touches_itself_is_made_again_nearer_the_boundary);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(contpath_suite)
