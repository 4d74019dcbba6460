#!/usr/bin/env python3
"""Run the Python tests (unittest) and finish with one line "python: N passed, N failed"."""

import os
import sys
import unittest

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)

# The struct layouts first: a ctypes mirror that differs from the C headers lets the library write past it
# (a segfault, or worse, silent corruption), so nothing else runs until they agree.
try:
    layout = unittest.defaultTestLoader.loadTestsFromName("test_layout")
except ImportError as e:  # the package refuses a library whose structs outgrew the mirrors (StaleMirror)
    print("python: cannot load the package: %s\npython: 0 passed, 1 failed" % e)
    sys.exit(1)
first = unittest.TextTestRunner(verbosity=int(os.environ.get("AMP_PY_VERBOSE", "1")), stream=sys.stdout).run(layout)
if not first.wasSuccessful():
    print("python: the ctypes mirrors in python/ampath/_lib.py differ from include/ampath/*.h (see above: "
          "mirror first, C second); fix them before the other tests run, which would crash\n"
          "python: 0 passed, %d failed (layout only)" % (len(first.failures) + len(first.errors)))
    sys.exit(1)

suite = unittest.defaultTestLoader.discover(here, pattern="test_*.py", top_level_dir=here)
suite = unittest.TestSuite(t for t in suite if "test_layout" not in repr(t))
result = unittest.TextTestRunner(verbosity=int(os.environ.get("AMP_PY_VERBOSE", "1")), stream=sys.stdout).run(suite)
failed = len(result.failures) + len(result.errors) + len(result.unexpectedSuccesses)
skipped = len(result.skipped) + len(first.skipped)
run = result.testsRun + first.testsRun
print("python: %d passed, %d failed%s" % (run - failed - skipped, failed,
                                          ", %d skipped" % skipped if skipped else ""))
sys.exit(0 if failed == 0 else 1)
