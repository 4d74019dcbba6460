/* ampath bench — the benchmarks of docs/interfaces.md §7, each printing ratios measured in the same run. */
#include <string.h>

#include "cli.h"

typedef struct bench {
    const char *name;
    int (*run)(cli_json *j, int quick);
} bench;

static const bench benches[] = {
#define AMP_BENCH(name) {#name, bench_##name},
#include "benches.inc"
#undef AMP_BENCH
    {NULL, NULL}};

const char cmd_bench_usage[] =
    "run the benchmarks (docs/interfaces.md 7) and print figures with same-run baselines\n"
    "usage: ampath bench [NAME...] [--quick] [--json]\n"
    "  NAME     run only the named benchmarks (default: all)\n"
    "  --quick  smaller sizes, for a smoke test\n";

int cmd_bench(int argc, char **argv)
{
    int json = 0, quick = 0, npos = 0, rc, i, failed = 0;
    const char *pos[32];
    const bench *b;
    cli_json j;
    cli_opt opts[] = {{"json", CLI_FLAG, &json, 0}, {"quick", CLI_FLAG, &quick, 0}, {NULL, CLI_FLAG, NULL, 0}};
    rc = cli_parse("bench", argc, argv, opts, pos, 0, 32, &npos);
    if (rc != CLI_OK)
        return rc;
    for (i = 0; i < npos; i++) {
        for (b = benches; b->name && strcmp(b->name, pos[i]) != 0; b++)
            ;
        if (!b->name)
            return cli_fail("bench", CLI_USAGE, "unknown benchmark '%s'", pos[i]);
    }
    if (json)
        cli_json_begin(&j, stdout);
    for (b = benches; b->name; b++) {
        int want = npos == 0;
        for (i = 0; i < npos; i++)
            want |= strcmp(b->name, pos[i]) == 0;
        if (!want)
            continue;
        if (json)
            cli_json_obj(&j, b->name);
        else
            printf("== %s\n", b->name);
        if (b->run(json ? &j : NULL, quick) != CLI_OK)
            failed = 1;
        if (json)
            cli_json_close(&j);
        else
            fflush(stdout);
    }
    if (json)
        cli_json_end(&j);
    return failed ? CLI_FAILED : CLI_OK;
}
