/* Run the ampath tool from a test (see fx_tool.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>

#include "fx_tool.h"
#include "testutil.h"

/* Run "$AMP_TOOL args" capturing up to @p cap bytes of stdout; returns the exit status. */
int fx_run_tool(const char *args, char *out, size_t cap)
{
    char cmd[1024];
    const char *tool = getenv("AMP_TOOL");
    FILE *p;
    size_t n = 0;
    int st;
    ck_assert_msg(tool != NULL, "AMP_TOOL not set");
    snprintf(cmd, sizeof cmd, "%s %s 2>/dev/null", tool, args);
    p = popen(cmd, "r");
    ck_assert(p != NULL);
    if (out) {
        n = fread(out, 1, cap - 1, p);
        out[n] = 0;
    } else {
        char buf[256];
        while (fread(buf, 1, sizeof buf, p) > 0)
            ;
    }
    st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

