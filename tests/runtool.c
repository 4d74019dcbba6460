/* Run the ampath tool from a test (see runtool.h). */
#define _XOPEN_SOURCE 600
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "runtool.h"
#include "testutil.h"

int fx_run_tool_stderr(const char *args, const char *stdin_text, char *err, size_t cap)
{
    char group[4096];
    /* the group's stdout to /dev/null and its stderr into the pipe; the tool's own redirections in args win */
    snprintf(group, sizeof group, "%s; } 2>&1 >/dev/null", args);
    return fx_run_tool_ex(group, stdin_text, 2, err, cap);
}

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
    if (with_stderr == 2) /* fx_run_tool_stderr: args end the group it opens here */
        snprintf(cmd, sizeof cmd, "{ %s <%s %s", tool ? tool : "tools/ampath", stdin_text ? infile : "/dev/null",
                 args);
    else
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

/* Append what the terminal's master @p m holds now (waiting up to @p ms for it); 0 when nothing came. */
static int drain(int m, int ms, char *err, size_t cap, size_t *n)
{
    struct pollfd pf;
    char buf[512];
    ssize_t k, i;
    pf.fd = m;
    pf.events = POLLIN;
    if (poll(&pf, 1, ms) <= 0 || !(pf.revents & POLLIN) || (k = read(m, buf, sizeof buf)) <= 0)
        return 0;
    for (i = 0; i < k; i++)
        if (*n + 1 < cap)
            err[(*n)++] = buf[i];
    return 1;
}

int fx_run_tool_tty(const char *args, char *err, size_t cap)
{
    const char *tool = getenv("AMP_TOOL");
    return fx_run_prog_tty(tool ? tool : "tools/ampath", args, err, cap);
}

int fx_run_prog_tty(const char *prog, const char *args, char *err, size_t cap)
{
    char cmd[4096];
    const char *slave;
    size_t n = 0;
    int m = posix_openpt(O_RDWR | O_NOCTTY), s, st = 0;
    pid_t pid;
    if (m < 0 || grantpt(m) != 0 || unlockpt(m) != 0 || !(slave = ptsname(m)))
        return -1;
    /* the slave held open here too, so that the master never reads as hung up while the tool starts */
    if ((s = open(slave, O_RDWR | O_NOCTTY)) < 0)
        return -1;
    snprintf(cmd, sizeof cmd, "exec %s %s </dev/null >/dev/null 2>%s", prog, args, slave);
    pid = fork();
    if (pid == 0) {
        close(m);
        close(s);
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    /* read while it runs (a full terminal would stall it), then what is left */
    while (waitpid(pid, &st, WNOHANG) == 0)
        drain(m, 50, err, cap, &n);
    while (drain(m, 0, err, cap, &n))
        ;
    if (cap)
        err[n] = 0;
    close(s);
    close(m);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int fx_run_tool(const char *args, char *out, size_t cap)
{
    return fx_run_tool_ex(args, NULL, 0, out, cap);
}
