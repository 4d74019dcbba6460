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

static Suite *exports_suite(void)
{
    Suite *s = suite_create("exports");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, shared_library_exports_exactly_the_declared_api);
    tcase_add_test(tc, comparison_names_an_internal_symbol_that_leaks);
    tcase_add_test(tc, geometry_tool_links_neither_the_bridge_nor_libserialport);
    suite_add_tcase(s, tc);
    return s;
}

FX_TEST_MAIN(exports_suite)
