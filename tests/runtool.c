/* Run the ampath tool from a test (see runtool.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "runtool.h"
#include "testutil.h"

int fx_run_tool_ex(const char *args, const char *stdin_text, int with_stderr, char *out, size_t cap)
{
    char cmd[4096], errfile[256], infile[256];
    const char *tool = getenv("AMP_TOOL");
    FILE *p;
    size_t n = 0;
    int c;
    /* per-process scratch names, not fx_tmp(): it recycles static buffers the caller may still hold */
    snprintf(errfile, sizeof errfile, "%s/ampath-test-%ld-tool-stderr.txt", fx_tmpdir(), (long)getpid());
    snprintf(infile, sizeof infile, "%s/ampath-test-%ld-tool-stdin.txt", fx_tmpdir(), (long)getpid());
    if (stdin_text) {
        FILE *f = fopen(infile, "w");
        if (!f)
            return -1;
        fputs(stdin_text, f);
        fclose(f);
    }
    snprintf(cmd, sizeof cmd, "%s %s <%s 2>%s", tool ? tool : "tools/ampath", args,
             stdin_text ? infile : "/dev/null", with_stderr ? "&1" : errfile);
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
    if (stdin_text)
        remove(infile);
    return WIFEXITED(c) ? WEXITSTATUS(c) : -1;
}

int fx_run_tool(const char *args, char *out, size_t cap)
{
    return fx_run_tool_ex(args, NULL, 0, out, cap);
}
