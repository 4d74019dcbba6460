/* runtool.h — run the ampath tool from a test (the one fixture every CLI test shares). */
#ifndef AMP_TEST_RUNTOOL_H
#define AMP_TEST_RUNTOOL_H

#include <stddef.h>

/**
 * Run "$AMP_TOOL args" (tools/ampath when unset) through the shell with stdin
 * from /dev/null, capture its stdout into @p out (NUL-terminated, at most
 * cap - 1 bytes; @p out may be NULL with cap 0; stderr is discarded) and
 * return its exit status (-1 if it did not exit).
 */
int fx_run_tool(const char *args, char *out, size_t cap);

/**
 * As fx_run_tool() but feeding @p stdin_text (NULL: nothing) on stdin,
 * and with @p with_stderr non-zero capturing stderr after stdout into @p out.
 */
int fx_run_tool_ex(const char *args, const char *stdin_text, int with_stderr, char *out, size_t cap);

/**
 * As fx_run_tool_ex() capturing only stderr into @p err; stdout goes where @p args redirect it (e.g.
 * ">/dev/full"), else to /dev/null.
 */
int fx_run_tool_stderr(const char *args, const char *stdin_text, char *err, size_t cap);

/**
 * As fx_run_tool() with stderr on a pseudo-terminal (as a user at a terminal sees it), which is read into
 * @p err (NUL-terminated, at most cap - 1 bytes); stdout is discarded. For the progress bars.
 */
int fx_run_tool_tty(const char *args, char *err, size_t cap);

/** As fx_run_tool_tty() for the program @p prog (a path: the bridge, the virtual printer). */
int fx_run_prog_tty(const char *prog, const char *args, char *err, size_t cap);

#endif
