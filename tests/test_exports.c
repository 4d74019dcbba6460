/*
 * The shared library's symbol table: it exports exactly the functions that the
 * public headers declare (tools/exports.sh lists them), so internal helpers
 * with the amp_ prefix (the lexer, the fragment BVH, the spline basis, ...)
 * are not part of what a user can link against.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#define MAXSYM 2048

typedef struct symset {
    char name[MAXSYM][64];
    int n;
} symset;

static int read_cmd(const char *cmd, symset *s)
{
    char line[512];
    FILE *f = popen(cmd, "r");
    if (!f)
        return -1;
    s->n = 0;
    while (fgets(line, sizeof line, f) && s->n < MAXSYM) {
        line[strcspn(line, "\r\n")] = 0;
        if (line[0] && strlen(line) < sizeof s->name[0])
            memcpy(s->name[s->n++], line, strlen(line) + 1);
    }
    return pclose(f) == 0 ? 0 : -1;
}

static int has(const symset *s, const char *name)
{
    int i;
    for (i = 0; i < s->n; i++)
        if (!strcmp(s->name[i], name))
            return 1;
    return 0;
}

/* Names in a but not in b, written to msg; their number. */
static int missing(const symset *a, const symset *b, char *msg, size_t cap)
{
    int i, k = 0;
    msg[0] = 0;
    for (i = 0; i < a->n; i++)
        if (!has(b, a->name[i])) {
            size_t len = strlen(msg);
            snprintf(msg + len, cap - len, " %s", a->name[i]);
            k++;
        }
    return k;
}

static const char *libso(void)
{
    const char *p = getenv("AMP_LIBSO");
    return p ? p : "lib/libampath.so";
}

static symset declared, exported;

START_TEST(shared_library_exports_exactly_the_declared_api)
{
    char cmd[1024], msg[8192];
    ck_assert_int_eq(read_cmd("sh tools/exports.sh include/ampath", &declared), 0);
    snprintf(cmd, sizeof cmd, "nm -D --defined-only '%s' | awk '$2 ~ /^[TWDBRV]$/ {print $3}'", libso());
    ck_assert_int_eq(read_cmd(cmd, &exported), 0);
    ck_assert_int_gt(declared.n, 150);
    ck_assert_msg(missing(&exported, &declared, msg, sizeof msg) == 0, "exported but not declared:%s", msg);
    ck_assert_msg(missing(&declared, &exported, msg, sizeof msg) == 0, "declared but not exported:%s", msg);
}
END_TEST

START_TEST(comparison_names_an_internal_symbol_that_leaks)
{
    /* the checker must be able to fail: an internal helper in the table is named */
    char msg[256];
    static symset decl, exp;
    decl.n = exp.n = 0;
    snprintf(decl.name[decl.n++], 64, "amp_spline_eval");
    snprintf(exp.name[exp.n++], 64, "amp_spline_eval");
    snprintf(exp.name[exp.n++], 64, "amp_lex_next");
    ck_assert_int_eq(missing(&exp, &decl, msg, sizeof msg), 1);
    ck_assert_str_eq(msg, " amp_lex_next");
    ck_assert_int_eq(missing(&decl, &exp, msg, sizeof msg), 0);
}
END_TEST

/* Symbols of program @p prog (static and dynamic, defined and undefined) that belong to the bridge (br_) or to
 * libserialport (sp_): the geometry tool links neither. */
static size_t bridge_symbols(const char *prog, symset *out)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "(nm '%s'; nm -D '%s') 2>/dev/null | awk '$NF ~ /^(br|sp)_/ {print $NF}' | sort -u",
             prog, prog);
    out->n = 0;
    ck_assert_int_eq(read_cmd(cmd, out), 0);
    return out->n;
}

START_TEST(geometry_tool_links_neither_the_bridge_nor_libserialport)
{
    static symset tool, bridge;
    /* the check can fail: the bridge program itself has both */
    ck_assert_int_gt(bridge_symbols(fx_prog("AMP_BRIDGE"), &bridge), 10);
    ck_assert_msg(bridge_symbols(fx_prog("AMP_TOOL"), &tool) == 0, "ampath has %s", tool.name[0]);
}
END_TEST

/* The public functions refuse a NULL where they need an object, and an out-of-range index or method, with
 * AMP_ERR_ARG and a message (status.h) — a black-box test of the headers found 14 that dereferenced it. */
START_TEST(public_functions_refuse_null_arguments_with_amp_err_arg)
{
    amp_pathset ps;
    amp_spline sp, *list = NULL;
    amp_fragments fs;
    amp_below_graph g;
    amp_head h;
    amp_error e;
    amp_vec3 pt;
    size_t n = 0;
    double par[3] = {0.5, 0.5, 0.5}, knot = 0.5;
    amp_status st[18];
    int k;
    amp_pathset_init(&ps, NULL);
    amp_spline_init(&sp);
    amp_head_default(&h);
    memset(&fs, 0, sizeof fs);
    amp_pathset_begin(&ps, AMP_ROLE_OBJECT, NULL);
    amp_pathset_push(&ps, amp_v3(0, 0, 0), 0.5, NULL);
    amp_pathset_push(&ps, amp_v3(1, 0, 0), 0.5, NULL);
    st[0] = amp_pathset_parse(NULL, "ampath-paths 1\n", 15, &e);
    st[1] = amp_pathset_begin(NULL, AMP_ROLE_OBJECT, &e);
    st[2] = amp_pathset_write(&ps, NULL, NULL, NULL, &e);
    st[3] = amp_spline_parse("ampath-spline 1\n", 16, NULL, NULL, &n, &e);
    st[4] = amp_spline_parse("ampath-spline 1\n", 16, NULL, &list, NULL, &e);
    st[5] = amp_spline_create(NULL, NULL, 1, NULL, NULL, 0, &e);
    st[6] = amp_spline_eval(NULL, par, &pt, &e);
    st[7] = amp_spline_eval(&sp, par, NULL, &e);
    st[8] = amp_trivariate_model("helix", NULL, NULL, &e);
    st[9] = amp_below_graph_build(&g, NULL, &h, 0, &e);
    st[10] = amp_tubes_union_volume(&ps, 100, NULL, &e);
    st[11] = amp_contpath_layers(NULL, NULL, &ps, NULL, &e);
    st[12] = amp_check_stroke(NULL, 3, NULL, 0.0, NULL, &e);
    st[13] = amp_check_path_stroke(&ps, 7, NULL, 0.0, NULL, &e);
    st[14] = amp_spline_write(&sp, 1, NULL, NULL, &e);
    st[15] = amp_check_gouge(&ps, &h, (amp_gouge_method)99, 0.0, NULL, &e);
    st[16] = amp_check_hold_runs(&ps, 1.0, NULL, NULL, &e);
    st[17] = amp_spline_refine(NULL, 0, &knot, 1, &e);
    for (k = 0; k < 18; k++)
        ck_assert_msg(st[k] == AMP_ERR_ARG, "call %d: status %d", k, (int)st[k]);
    amp_pathset_free(&ps);
}
END_TEST

static Suite *exports_suite(void)
{
    Suite *s = suite_create("exports");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, shared_library_exports_exactly_the_declared_api);
    tcase_add_test(tc, comparison_names_an_internal_symbol_that_leaks);
    tcase_add_test(tc, geometry_tool_links_neither_the_bridge_nor_libserialport);
    tcase_add_test(tc, public_functions_refuse_null_arguments_with_amp_err_arg);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(exports_suite)
