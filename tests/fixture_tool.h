/* fixture_tool.h — run `tools/ampath` (found through $AMP_TOOL) from a test. */
#ifndef AMP_FIXTURE_TOOL_H
#define AMP_FIXTURE_TOOL_H

#include <stddef.h>

/**
 * Run "$AMP_TOOL ARGS" with stderr discarded; its stdout goes to @p out
 * (NUL-terminated, at most cap-1 bytes) when @p out is not NULL. Returns the
 * exit status, -1 if it did not exit normally, -2 if AMP_TOOL is not set.
 */
int amp_test_run_tool(const char *args, char *out, size_t cap);

#endif
