/* Run the ampath tool from a test (see runtool.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "runtool.h"

int amp_test_run_tool(const char *args, char *out, size_t cap)
{
    char cmd[4096], errfile[256];
    const char *tool = getenv("AMP_TOOL");
    FILE *p;
    size_t n = 0;
    int c;
    /* not amp_test_tmp(): it recycles a few static buffers that the caller may still hold */
    snprintf(errfile, sizeof errfile, "/tmp/ampath-test-%ld-tool-stderr.txt", (long)getpid());
    snprintf(cmd, sizeof cmd, "%s %s 2>%s", tool ? tool : "tools/ampath", args, errfile);
    p = popen(cmd, "r");
    if (!p)
        return -1;
    while ((c = fgetc(p)) != EOF)
        if (n + 1 < cap)
            out[n++] = (char)c;
    if (cap)
        out[n < cap ? n : cap - 1] = 0;
    c = pclose(p);
    remove(errfile);
    return WIFEXITED(c) ? WEXITSTATUS(c) : -1;
}
