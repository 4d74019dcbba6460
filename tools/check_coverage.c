/* `ampath check` coverage checker (paper 1, §4): picks the model's measure. */
#include "checkers.h"

/* Coverage is a property of the object paths: support lies outside the model and covers nothing of it. */
static int run_on_objects(const check_ctx *c, cli_json *j, int (*run)(const check_ctx *, cli_json *))
{
    amp_pathset obj;
    check_ctx co = *c;
    amp_error err;
    size_t i, segs = 0;
    int rc;
    for (i = 0; i < c->ps->npaths; i++)
        segs += c->ps->paths[i].role == AMP_ROLE_OBJECT && c->ps->paths[i].n > 1;
    if (segs == 0) { /* nothing covers the model: a failed check, not bad input */
        if (j) {
            cli_json_bool(j, "ran", 1);
            cli_json_bool(j, "ok", 0);
            cli_json_str(j, "reason", "no object path with a segment");
        } else {
            fprintf(c->out, "coverage: no object path with a segment covers the model: FAILED\n");
        }
        return CLI_FAILED;
    }
    for (i = 0; i < c->ps->npaths && c->ps->paths[i].role == AMP_ROLE_OBJECT; i++)
        ;
    if (i == c->ps->npaths)
        return run(c, j);
    amp_error_clear(&err);
    amp_pathset_init(&obj, NULL);
    for (i = 0; i < c->ps->npaths; i++)
        if (c->ps->paths[i].role == AMP_ROLE_OBJECT &&
            amp_pathset_add(&obj, AMP_ROLE_OBJECT, amp_pathset_path_verts(c->ps, i), c->ps->paths[i].n, &err) != AMP_OK) {
            amp_pathset_free(&obj);
            return cli_fail_err("check", &err);
        }
    co.ps = &obj;
    rc = run(&co, j);
    amp_pathset_free(&obj);
    return rc;
}

int check_coverage(const check_ctx *c, cli_json *j)
{
    const char *why = NULL;
    if (c->trivariate)
        return run_on_objects(c, j, check_trivariate);
    if (c->mesh && !c->layer_given)
        return run_on_objects(c, j, check_mesh);
    /* With --layer the mesh was sliced: layer strokes are checked against its polygons instead. */
    why = c->mesh ? "--layer given: the mesh is used for the stroke check" : "no model (--trivariate or --mesh)";
    if (j) {
        cli_json_bool(j, "ran", 0);
        cli_json_str(j, "reason", why);
    } else {
        fprintf(c->out, "coverage: not run (%s)\n", why);
    }
    return CLI_OK;
}
