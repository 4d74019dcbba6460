/*
 * Benchmark (docs/interfaces.md §7): the bridge's throughput as a part of `ampath bench`. It is measured by
 * `ampath-bridge --bench` (bridge/bench.c) in a child process, so that the geometry tool links neither the
 * bridge nor libserialport; its figures are shown here as they come.
 */
#define _DEFAULT_SOURCE
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"


/* The child's JSON object {"bridge":[...],...} as members of the open object: braces and blanks trimmed. */
static void put_members(cli_json *j, char *text)
{
    char *a = strchr(text, '{'), *b = strrchr(text, '}');
    if (!a || !b || b <= a) {
        cli_json_str(j, "error", "ampath-bridge --bench wrote no JSON object");
        return;
    }
    *b = '\0';
    if (a[1])
        cli_json_members(j, a + 1);
}

int bench_bridge(cli_json *j, int quick)
{
    char prog[PATH_MAX], cmd[PATH_MAX + 64], buf[4096], *text = NULL;
    size_t len = 0, n;
    FILE *p;
    int st;
    if (cli_program("AMP_BRIDGE", "ampath-bridge", "bridge", prog, sizeof prog) != 0 || access(prog, X_OK) != 0) {
        fprintf(stderr, "ampath bench: bridge: ampath-bridge not found (set AMP_BRIDGE)\n");
        return CLI_FAILED;
    }
    snprintf(cmd, sizeof cmd, "'%s' --bench%s%s", prog, quick ? " --quick" : "", j ? " --json" : "");
    fflush(stdout);
    if (!(p = popen(cmd, "r")))
        return CLI_FAILED;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) {
        char *t;
        if (!j) {
            fwrite(buf, 1, n, stdout);
            continue;
        }
        if (!(t = realloc(text, len + n + 1)))
            break;
        text = t;
        memcpy(text + len, buf, n);
        len += n;
        text[len] = '\0';
    }
    st = pclose(p);
    if (j && text)
        put_members(j, text);
    free(text);
    return st != -1 && WIFEXITED(st) && WEXITSTATUS(st) == 0 ? CLI_OK : CLI_FAILED;
}
