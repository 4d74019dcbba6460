/* ampath info FILE — what a path or mesh file holds. */
#include <string.h>

#include "cli.h"

const char cmd_info_usage[] =
    "describe a path (.amp) file: paths, vertices, lengths, radii, bounding box\n"
    "usage: ampath info FILE.amp [--json]\n";

static int info_paths(const char *file, int json)
{
    amp_pathset ps;
    amp_box3 b;
    double rmin = 0.0, rmax = 0.0;
    size_t i, nsupport = 0;
    int rc;
    amp_pathset_init(&ps, NULL);
    rc = cli_load_paths("info", file, &ps);
    if (rc != CLI_OK)
        return rc;
    for (i = 0; i < ps.nverts; i++) {
        if (i == 0 || ps.verts[i].r < rmin)
            rmin = ps.verts[i].r;
        if (i == 0 || ps.verts[i].r > rmax)
            rmax = ps.verts[i].r;
    }
    for (i = 0; i < ps.npaths; i++)
        nsupport += ps.paths[i].role == AMP_ROLE_SUPPORT;
    b = amp_pathset_bbox(&ps);
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "kind", "paths");
        cli_json_int(&j, "paths", (long long)ps.npaths);
        cli_json_int(&j, "support_paths", (long long)nsupport);
        cli_json_int(&j, "vertices", (long long)ps.nverts);
        cli_json_num(&j, "length_mm", amp_pathset_length(&ps, -1));
        cli_json_num(&j, "volume_mm3", amp_pathset_volume(&ps, -1));
        cli_json_num(&j, "r_min", rmin);
        cli_json_num(&j, "r_max", rmax);
        cli_json_arr(&j, "bbox");
        cli_json_num(&j, NULL, b.min.x);
        cli_json_num(&j, NULL, b.min.y);
        cli_json_num(&j, NULL, b.min.z);
        cli_json_num(&j, NULL, b.max.x);
        cli_json_num(&j, NULL, b.max.y);
        cli_json_num(&j, NULL, b.max.z);
        cli_json_end(&j);
    } else {
        printf("%s: %lu paths (%lu support), %lu vertices\n", file, (unsigned long)ps.npaths,
               (unsigned long)nsupport, (unsigned long)ps.nverts);
        printf("length %.3f mm, deposited volume %.3f mm^3, radius %.3f .. %.3f mm\n",
               amp_pathset_length(&ps, -1), amp_pathset_volume(&ps, -1), rmin, rmax);
        if (ps.nverts)
            printf("bbox (%.3f %.3f %.3f) .. (%.3f %.3f %.3f)\n", b.min.x, b.min.y, b.min.z, b.max.x, b.max.y,
                   b.max.z);
    }
    amp_pathset_free(&ps);
    return CLI_OK;
}

int cmd_info(int argc, char **argv)
{
    int json = 0, npos = 0, rc;
    const char *pos[1];
    cli_opt opts[] = {{"json", CLI_FLAG, &json, 0}, {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("info", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    return info_paths(pos[0], json);
}
