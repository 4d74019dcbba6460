/*
 * Benchmark: BVH build time and inside tests per second on the helix mesh,
 * against the brute-force winding number (every triangle per query) measured
 * in the same run; also checks that both agree away from the surface.
 */
#include "cli.h"

static double frand(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
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
        amp_vec3 p = amp_v3(box.min.x + frand(&s) * (box.max.x - box.min.x),
                            box.min.y + frand(&s) * (box.max.y - box.min.y),
                            box.min.z + frand(&s) * (box.max.z - box.min.z));
        inside += (size_t)amp_bvh_inside(b, p);
    }
    t_fast = cli_now() - t0;
    s = 7;
    t0 = cli_now();
    for (i = 0; i < nbrute; i++) {
        amp_vec3 p = amp_v3(box.min.x + frand(&s) * (box.max.x - box.min.x),
                            box.min.y + frand(&s) * (box.max.y - box.min.y),
                            box.min.z + frand(&s) * (box.max.z - box.min.z));
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
    amp_mesh_free(&m);
    return rc;
}
