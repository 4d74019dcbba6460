/* runtool.h — run the ampath tool from a test (fixture shared by the order, mdr and support tests). */
#ifndef AMP_TEST_RUNTOOL_H
#define AMP_TEST_RUNTOOL_H

#include <stddef.h>

/**
 * Run "$AMP_TOOL args" (tools/ampath when unset) through the shell, capture
 * its stdout into @p out (NUL-terminated, at most cap - 1 bytes; stderr goes
 * to a scratch file) and return its exit status (-1 if it did not exit).
 */
int amp_test_run_tool(const char *args, char *out, size_t cap);

#endif
