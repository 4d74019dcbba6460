/* ampath model NAME -o FILE — write a built-in model (docs/interfaces.md §4). */
#include <stdio.h>
#include <string.h>

#include "cli.h"

const char cmd_model_usage[] =
    "write a built-in model: a trivariate (.spl) or a mesh (.stl)\n"
    "usage: ampath model NAME -o FILE [--json]\n"
    "  NAME       helix          disc of radius 5 mm swept along a helix of radius 20 mm, pitch 40 mm\n"
    "                            ([P1] Fig. 2; docs/interfaces.md §4.2), lowest point on z = 0\n"
    "             torus-quarter  paper Fig. 4 torus quarter (major 1, minor 0.2) scaled x50:\n"
    "                            major radius 50 mm, minor 10 mm, resting on z = 0\n"
    "             vase           paper Fig. 18: revolved wall 60 mm high, radii 9..30 mm, wall 3..12 mm\n"
    "  meshes (-o FILE.stl): helix (boundary of the same solid, within 0.05 mm), twisted-bridge\n"
    "             (paper Fig. 15), crocodile-like (organic shape with thin limbs); see docs/mesh.md;\n"
    "             torus-quarter and vase: the tessellated boundary of the trivariate\n"
    "  -o FILE    output; FILE ending in .stl writes the mesh of the model (binary STL),\n"
    "             anything else the trivariate as .spl\n"
    "  --tol T    mesh models: largest distance to the exact surface, mm (default 0.05)\n"
    "  --json     print {\"model\", \"file\", \"kind\", counts, \"bbox\"} on stdout\n";

static int write_mesh_model(const char *name, const char *out, double tol, int json)
{
    amp_mesh m;
    amp_error err;
    amp_error_clear(&err);
    amp_mesh_init(&m, NULL);
    if (amp_mesh_model(name, tol, &m, &err) != AMP_OK) {
        /* No mesh of that name: the boundary of the trivariate model of that name. */
        amp_spline v;
        amp_error err2;
        amp_error_clear(&err2);
        if (amp_trivariate_model(name, NULL, &v, &err2) != AMP_OK)
            return cli_fail_err("model", &err);
        amp_error_clear(&err);
        if (amp_mesh_from_trivariate(&m, &v, 0, &err) != AMP_OK) {
            amp_spline_free(&v);
            return cli_fail_err("model", &err);
        }
        amp_spline_free(&v);
    }
    if (amp_mesh_write_stl_file(&m, out, 1, &err) != AMP_OK) {
        amp_mesh_free(&m);
        return cli_fail_err("model", &err);
    }
    if (json) {
        cli_json j;
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "model", name);
        cli_json_str(&j, "file", out);
        cli_json_str(&j, "kind", "mesh");
        cli_json_int(&j, "triangles", (long long)m.ntris);
        cli_json_int(&j, "vertices", (long long)m.nverts);
        cli_json_box(&j, "bbox", amp_mesh_bbox(&m));
        cli_json_end(&j);
    } else {
        amp_box3 bb = amp_mesh_bbox(&m);
        printf("%s: mesh, %lu triangles, %.1f x %.1f x %.1f mm -> %s\n", name, (unsigned long)m.ntris,
               bb.max.x - bb.min.x, bb.max.y - bb.min.y, bb.max.z - bb.min.z, out);
    }
    amp_mesh_free(&m);
    return CLI_OK;
}

/* amp_writer_fn for amp_write_file_atomic(): the trivariate with its header */
static amp_status spline_writer(void *ctx, amp_sink_fn sink, void *user, amp_error *err)
{
    return amp_spline_write(ctx, 1, sink, user, err);
}

int cmd_model(int argc, char **argv)
{
    const char *pos[1], *out = NULL;
    int json = 0, npos = 0, rc;
    double tol = 0.0;
    amp_spline s;
    amp_error err;
    cli_opt opts[] = {{"output", CLI_STR, &out, 0}, {"json", CLI_FLAG, &json, 0}, {"tol", CLI_DOUBLE, &tol, 0}, {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("model", argc, argv, opts, pos, 1, 1, &npos);
    if (rc != CLI_OK)
        return rc;
    if (!out)
        return cli_fail("model", CLI_USAGE, "-o FILE is required (.spl or .stl)");
    if (cli_ends_with(out, ".stl") || cli_ends_with(out, ".STL"))
        return write_mesh_model(pos[0], out, tol, json);
    amp_error_clear(&err);
    if (amp_trivariate_model(pos[0], NULL, &s, &err) != AMP_OK)
        return cli_fail_err("model", &err);
    if (amp_write_file_atomic(out, spline_writer, &s, &err) != AMP_OK) {
        amp_spline_free(&s);
        return cli_fail_err("model", &err);
    }
    if (json) {
        cli_json j;
        amp_box3 b = amp_spline_cp_bbox(&s);
        cli_json_begin(&j, stdout);
        cli_json_str(&j, "model", pos[0]);
        cli_json_str(&j, "file", out);
        cli_json_str(&j, "kind", "trivariate");
        cli_json_int(&j, "control_points", (long long)s.ncp);
        cli_json_box(&j, "bbox", b);
        cli_json_end(&j);
    } else {
        printf("%s: trivariate, %lu control points -> %s\n", pos[0], (unsigned long)s.ncp, out);
    }
    amp_spline_free(&s);
    return CLI_OK;
}
