/* `ampath check` coverage checker (paper 1, §4): picks the model's measure. */
#include "checkers.h"

int check_coverage(const check_ctx *c, cli_json *j)
{
    const char *why = NULL;
    if (c->trivariate)
        return check_trivariate(c, j);
    if (c->mesh && !c->layer_given)
        return check_mesh(c, j);
    /* With --layer the mesh was sliced: layer strokes are checked against its polygons instead. */
    why = c->mesh ? "--layer given: the mesh is used for the stroke check" : "no model (--trivariate or --mesh)";
    if (j) {
        cli_json_bool(j, "ran", 0);
        cli_json_str(j, "reason", why);
    } else {
        printf("coverage: not run (%s)\n", why);
    }
    return CLI_OK;
}
