/* fx_tool.h — run the ampath tool from a test (AMP_TOOL). */
#ifndef AMP_FX_TOOL_H
#define AMP_FX_TOOL_H

#include <stddef.h>

/** Run "$AMP_TOOL args" (stderr discarded), capturing up to @p cap - 1 bytes
 * of stdout into @p out (NUL-terminated; out may be NULL). Returns the exit
 * status, -1 when the program did not exit normally. */
int fx_run_tool(const char *args, char *out, size_t cap);

#endif
