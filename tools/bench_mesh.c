/*
 * Benchmark: BVH build time and inside tests per second on the helix mesh,
 * against the brute-force winding number (every triangle per query) measured
 * in the same run; also checks that both agree away from the surface. The
 * same mesh opened by holes: inside tests by rays over its caps against the
 * hierarchical generalised winding number (the open meshes' test before the
 * caps), same run, same points.
 */
#include "cli.h"

static double frand(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* A point drawn uniformly in @p box. */
static amp_vec3 rand_in(amp_box3 box, unsigned long long *s)
{
    double x = frand(s), y = frand(s), z = frand(s);
    return amp_v3(box.min.x + x * (box.max.x - box.min.x), box.min.y + y * (box.max.y - box.min.y),
                  box.min.z + z * (box.max.z - box.min.z));
}

/* The helix mesh with every 40th triangle taken out: caps and rays against the generalised winding number. */
static int open_mesh(cli_json *j, amp_mesh *m, int quick)
{
    amp_bvh *b = NULL;
    amp_error err;
    amp_box3 box;
    size_t i, n = quick ? 5000 : 50000, in_cap = 0, in_wind = 0, holes = 0;
    double t0, t_cap, t_wind;
    unsigned long long s = 3;
    for (i = 0; i < m->ntris; i += 40, holes++)
        m->tris[i] = m->tris[--m->ntris];
    if (amp_bvh_build(&b, m, &err) != AMP_OK)
        return cli_fail_err("bench", &err);
    box = amp_bvh_bbox(b);
    t0 = cli_now();
    for (i = 0; i < n; i++)
        in_cap += (size_t)amp_bvh_inside(b, rand_in(box, &s));
    t_cap = cli_now() - t0;
    s = 3; /* the same points */
    t0 = cli_now();
    for (i = 0; i < n; i++)
        in_wind += amp_bvh_winding(b, rand_in(box, &s)) >= 0.5;
    t_wind = cli_now() - t0;
    if (j) {
        cli_json_int(j, "open_cap_triangles", amp_bvh_cap_triangles(b));
        cli_json_num(j, "open_inside_per_s", n / cli_positive(t_cap));
        cli_json_num(j, "open_winding_per_s", n / cli_positive(t_wind));
        cli_json_num(j, "open_speedup", t_wind / cli_positive(t_cap));
        cli_json_int(j, "open_count_difference", (long long)in_cap - (long long)in_wind);
    } else
        printf("opened by %lu holes (%ld cap triangles): inside tests %.0f /s by rays over the caps, %.0f /s by the "
               "generalised winding number: %.1fx faster; inside counts differ by %ld of %lu\n",
               (unsigned long)holes, amp_bvh_cap_triangles(b), n / cli_positive(t_cap),
               n / cli_positive(t_wind), t_wind / cli_positive(t_cap), (long)in_cap - (long)in_wind, (unsigned long)n);
    amp_bvh_free(b);
    return CLI_OK;
}

int bench_mesh(cli_json *j, int quick)
{
    amp_mesh m;
    amp_bvh *b = NULL;
    amp_error err;
    amp_box3 box;
    double t0, t_build, t_fast, t_brute, rate_fast, rate_brute;
    size_t nfast = quick ? 20000 : 400000, nbrute = quick ? 200 : 2000, i, inside = 0, disagree = 0;
    unsigned long long s = 1;
    int rc = CLI_OK;
    amp_mesh_init(&m, NULL);
    if (amp_mesh_model("helix", 0.01, &m, &err) != AMP_OK)
        return cli_fail_err("bench", &err);
    t0 = cli_now();
    if (amp_bvh_build(&b, &m, &err) != AMP_OK) {
        amp_mesh_free(&m);
        return cli_fail_err("bench", &err);
    }
    t_build = cli_now() - t0;
    box = amp_bvh_bbox(b);
    t0 = cli_now();
    for (i = 0; i < nfast; i++) {
        inside += (size_t)amp_bvh_inside(b, rand_in(box, &s));
    }
    t_fast = cli_now() - t0;
    s = 7;
    t0 = cli_now();
    for (i = 0; i < nbrute; i++) {
        amp_vec3 p = rand_in(box, &s);
        double w = amp_bvh_winding_exact(b, p);
        if ((w >= 0.5) != amp_bvh_inside(b, p) && (w - 0.5) * (w - 0.5) > 0.05 * 0.05)
            disagree++;
    }
    t_brute = cli_now() - t0; /* includes nbrute fast queries: negligible next to the brute force */
    rate_fast = nfast / cli_positive(t_fast);
    rate_brute = nbrute / cli_positive(t_brute);
    if (disagree)
        rc = CLI_FAILED;
    if (j) {
        cli_json_int(j, "triangles", (long long)m.ntris);
        cli_json_num(j, "bvh_build_s", t_build);
        cli_json_num(j, "inside_per_s", rate_fast);
        cli_json_num(j, "brute_inside_per_s", rate_brute);
        cli_json_num(j, "speedup", rate_fast / rate_brute);
        cli_json_num(j, "inside_fraction", (double)inside / (double)nfast);
        cli_json_int(j, "disagreements", (long long)disagree);
    } else {
        printf("helix mesh (tol 0.01 mm) %lu triangles: BVH build %.3f s\n", (unsigned long)m.ntris, t_build);
        printf("inside tests: %.0f /s with the BVH winding number, %.0f /s brute force: %.1fx faster, "
               "%lu disagreements\n",
               rate_fast, rate_brute, rate_fast / rate_brute, (unsigned long)disagree);
    }
    amp_bvh_free(b);
    if (rc == CLI_OK)
        rc = open_mesh(j, &m, quick);
    amp_mesh_free(&m);
    return rc;
}
