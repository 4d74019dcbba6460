#!/usr/bin/env python3
"""Run the Python tests (unittest) and finish with one line "python: N passed, N failed"."""

import os
import sys
import unittest

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
suite = unittest.defaultTestLoader.discover(here, pattern="test_*.py", top_level_dir=here)
result = unittest.TextTestRunner(verbosity=int(os.environ.get("AMP_PY_VERBOSE", "1")), stream=sys.stdout).run(suite)
failed = len(result.failures) + len(result.errors) + len(result.unexpectedSuccesses)
skipped = len(result.skipped)
print("python: %d passed, %d failed%s" % (result.testsRun - failed - skipped, failed,
                                          ", %d skipped" % skipped if skipped else ""))
sys.exit(0 if failed == 0 else 1)
