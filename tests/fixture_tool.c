/* Running tools/ampath from tests (popen; POSIX). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>

#include "fixture_tool.h"

int amp_test_run_tool(const char *args, char *out, size_t cap)
{
    char cmd[4096], sink[4096];
    const char *tool = getenv("AMP_TOOL");
    FILE *p;
    size_t n = 0;
    int st;
    if (!tool)
        return -2;
    snprintf(cmd, sizeof cmd, "%s %s 2>/dev/null", tool, args);
    p = popen(cmd, "r");
    if (!p)
        return -1;
    if (out && cap > 0) {
        n = fread(out, 1, cap - 1, p);
        out[n] = '\0';
    }
    while (fread(sink, 1, sizeof sink, p) > 0)
        ;
    st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
