"""Shared helpers of the Python tests: where the programs are, running the tool, comparing outputs."""

import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.normpath(os.path.join(HERE, "..")))

import ampath  # noqa: E402  (the package of this tree, found through sys.path above)


def program(var, rel):
    """A program of the tree: $VAR (as make check sets it) or the in-tree build."""
    return os.environ.get(var) or os.path.join(ROOT, rel)


TOOL = program("AMP_TOOL", "tools/ampath")
BRIDGE = program("AMP_BRIDGE", "bridge/ampath-bridge")
VPRINTER = program("AMP_VPRINTER", "tools/ampath-vprinter")


def tool(*args, ok=True):
    """Run `ampath ARGS`; returns the CompletedProcess (stdout, stderr as text)."""
    r = subprocess.run([TOOL] + [str(a) for a in args], capture_output=True, text=True, timeout=600)
    if ok and r.returncode != 0:
        raise AssertionError("ampath %s failed (%d): %s" % (" ".join(map(str, args)), r.returncode, r.stderr))
    return r


def tool_message(cmd, stderr):
    """The library message of a tool failure: stderr is 'ampath CMD: MESSAGE'."""
    line = stderr.strip().splitlines()[-1]
    prefix = "ampath %s: " % cmd
    assert line.startswith(prefix), line
    return line[len(prefix):]


def strip_comments(data):
    """`.amp` bytes without the `#` provenance lines (they name the tool's input files)."""
    if isinstance(data, str):
        data = data.encode()
    return b"".join(l for l in data.splitlines(True) if not l.startswith(b"#"))


def as_tool_prints(x):
    """A figure as `ampath ... --json` prints it: %.12g, non-finite as null; timings dropped."""
    if isinstance(x, dict):
        return {k: as_tool_prints(v) for k, v in x.items() if k not in ("time_s", "input")}
    if isinstance(x, (list, tuple)):
        return [as_tool_prints(v) for v in x]
    if isinstance(x, float):
        return float("%.12g" % x) if math.isfinite(x) else None
    return x


def read(path):
    with open(path, "rb") as f:
        return f.read()


class TmpCase(unittest.TestCase):
    """A test case with its own temporary directory (self.tmp, self.p(name))."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="ampath-py-")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def p(self, name):
        return os.path.join(self.tmp, name)

    def assertSameBytes(self, a, b, what):
        if a != b:
            n = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y), min(len(a), len(b)))
            self.fail("%s differs at byte %d (%d vs %d bytes): %r vs %r" % (what, n, len(a), len(b),
                                                                         a[max(0, n - 40):n + 40],
                                                                         b[max(0, n - 40):n + 40]))
