/* ampath info FILE — what a path or mesh file holds. */
#include <string.h>

#include "cli.h"

const char cmd_info_usage[] =
    "describe a path (.amp) or mesh (.stl) file\n"
    "usage: ampath info FILE.amp|FILE.stl [--json]\n"
    "  FILE.amp   paths, support paths, vertices, length (mm), deposited volume (mm^3), radius range, bounding box\n"
    "  FILE.stl   (binary or ASCII, chosen by the .stl extension, any case) format, triangles in the file,\n"
    "             triangles kept, degenerate (zero-area) triangles dropped, duplicate triangles dropped (copies,\n"
    "             and faces met in both orientations), welded vertices, bounding box (mm),\n"
    "             signed volume (mm^3), closedness: boundary, non-manifold and misoriented edges\n"
    "  --json     print one JSON object instead of text (default: off)\n"
    "exit status: 0 ok, 2 bad usage or unreadable/malformed file\n";

static int has_stl_ext(const char *f)
{
    size_t n = strlen(f);
    return n >= 4 && f[n - 4] == '.' && (f[n - 3] | 32) == 's' && (f[n - 2] | 32) == 't' && (f[n - 1] | 32) == 'l';
}

static int info_mesh(const char *file, int json)
{
    amp_mesh m;
    amp_stl_stats st;
    amp_mesh_edge_report er;
    amp_error err;
    amp_box3 b;
    double vol;
    amp_error_clear(&err);
    amp_mesh_init(&m, NULL);
    if (amp_mesh_read_stl_file_ex(&m, file, &st, &err) != AMP_OK || amp_mesh_edges(&m, &er, &err) != AMP_OK) {
        amp_mesh_free(&m);
        return cli_fail_err("info", &err);
    }
    b = amp_mesh_bbox(&m);
    vol = amp_mesh_volume(&m);
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "kind", "mesh");
        cli_json_str(&j, "format", st.binary ? "binary" : "ascii");
        cli_json_int(&j, "triangles_in_file", (long long)st.triangles);
        cli_json_int(&j, "triangles", (long long)m.ntris);
        cli_json_int(&j, "degenerate", (long long)st.degenerate);
        cli_json_int(&j, "duplicates", (long long)st.duplicates);
        cli_json_int(&j, "tjunctions", (long long)st.tjunctions);
        cli_json_int(&j, "near_welded", (long long)st.near_welded);
        cli_json_int(&j, "vertices", (long long)m.nverts);
        cli_json_num(&j, "volume_mm3", vol);
        cli_json_bool(&j, "closed", er.closed);
        cli_json_int(&j, "edges", (long long)er.edges);
        cli_json_int(&j, "boundary_edges", (long long)er.boundary);
        cli_json_int(&j, "nonmanifold_edges", (long long)er.nonmanifold);
        cli_json_int(&j, "misoriented_edges", (long long)er.misoriented);
        cli_json_box(&j, "bbox", b);
        cli_json_end(&j);
    } else {
        printf("%s: %s STL, %lu triangles (%lu degenerate dropped, %lu duplicates dropped", file,
               st.binary ? "binary" : "ASCII", (unsigned long)m.ntris, (unsigned long)st.degenerate,
               (unsigned long)st.duplicates);
        if (st.tjunctions)
            printf(", split at %lu T-junctions", (unsigned long)st.tjunctions);
        if (st.near_welded)
            printf(", %lu vertices merged into a neighbour under 1e-9 of the diagonal away", (unsigned long)st.near_welded);
        printf("), %lu vertices after welding\n", (unsigned long)m.nverts);
        printf("bbox (%.3f %.3f %.3f) .. (%.3f %.3f %.3f), volume %.3f mm^3\n", b.min.x, b.min.y, b.min.z, b.max.x,
               b.max.y, b.max.z, vol);
        printf("%s: %lu edges, %lu boundary, %lu non-manifold, %lu misoriented\n",
               er.closed ? "closed" : "NOT closed", (unsigned long)er.edges, (unsigned long)er.boundary,
               (unsigned long)er.nonmanifold, (unsigned long)er.misoriented);
    }
    amp_mesh_free(&m);
    return CLI_OK;
}

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
        cli_json_box(&j, "bbox", b);
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
    return has_stl_ext(pos[0]) ? info_mesh(pos[0], json) : info_paths(pos[0], json);
}
