"""The ctypes mirrors of the C structs (ampath/_lib.py STRUCTS) have the C layout: every field's offset and
every struct's size compared with what the C compiler says for include/ampath/*.h. After a header change
this test names the struct and field to update in _lib.py. Needs a C compiler (make check has one)."""

import ctypes
import os
import shutil
import subprocess
import sys
import unittest

# the package refuses to load when an options mirror is too small (_lib.probe_default); here the comparison
# below is wanted instead, since it names every field that differs
os.environ["AMPATH_LAYOUT_PROBE"] = "0"
from amptest import ROOT, TmpCase  # noqa: E402

from ampath import _lib as L  # noqa: E402

CC = os.environ.get("CC", "cc")


@unittest.skipUnless(shutil.which(CC), "no C compiler")
class Layout(TmpCase):
    maxDiff = None  # every differing field named
    def differences(self, structs):
        """[(mirror, C)] lines that differ: 'NAME SIZE' and 'NAME.FIELD OFFSET'."""
        lines = ["#include <stddef.h>", "#include <stdio.h>", "#include \"ampath/ampath.h\"", "int main(void) {"]
        expect = []
        for name, cls in sorted(structs.items()):
            lines.append('printf("%s %%zu\\n", sizeof(%s));' % (name, name))
            expect.append("%s %d" % (name, ctypes.sizeof(cls)))
            for field, _ in cls._fields_:
                lines.append('printf("%s.%s %%zu\\n", offsetof(%s, %s));' % (name, field, name, field))
                expect.append("%s.%s %d" % (name, field, getattr(cls, field).offset))
        lines += ["return 0;", "}"]
        src, exe = self.p("layout.c"), self.p("layout")
        with open(src, "w") as f:
            f.write("\n".join(lines) + "\n")
        subprocess.run([CC, "-std=c99", "-I", os.path.join(ROOT, "include"), src, "-o", exe], check=True)
        got = subprocess.run([exe], capture_output=True, text=True, check=True).stdout.split("\n")[:-1]
        self.assertEqual(len(got), len(expect))
        return [(e, g) for e, g in zip(expect, got) if e != g]

    def test_every_mirrored_struct_has_the_c_layout(self):
        self.assertEqual(self.differences(L.STRUCTS), [], "ctypes mirror (first) differs from C (second)")

    def test_the_comparison_sees_a_stale_mirror(self):
        class amp_head(ctypes.Structure):  # fields in the wrong order
            _fields_ = [("theta", ctypes.c_double), ("z_offs", ctypes.c_double)]
        self.assertEqual(self.differences({"amp_head": amp_head}),
                         [("amp_head.theta 0", "amp_head.theta 8"), ("amp_head.z_offs 8", "amp_head.z_offs 0")])


class Guards(unittest.TestCase):
    """Without a compiler: a mirror smaller than its C struct is refused before the library writes past it."""

    class old_contpath_opts(ctypes.Structure):  # amp_contpath_opts before tour, skins and join (48 bytes)
        _fields_ = [("radius", ctypes.c_double), ("cell", ctypes.c_double), ("grid", ctypes.c_int),
                    ("offset", ctypes.c_double), ("perimeters", ctypes.c_int), ("support_stretches", ctypes.c_int),
                    ("pseudo_edges", ctypes.c_int)]

    def test_an_outdated_options_mirror_is_refused(self):
        with self.assertRaises(L.StaleMirror) as cm:
            L.probe_default(self.old_contpath_opts, "amp_contpath_opts_default", (0.225,), L.amp_contpath_opts)
        self.assertIn("old_contpath_opts", str(cm.exception))
        for cls, fn, args in L.DEFAULTS:  # the current mirrors pass (as at import)
            L.probe_default(cls, fn, args)

    def test_the_package_probes_at_import(self):
        env = dict(os.environ)
        env.pop("AMPATH_LAYOUT_PROBE")
        code = "import ampath._lib as L; print(L.probe_default.__name__)"
        r = subprocess.run([sys.executable, "-c", code], env=env, cwd=os.path.join(ROOT, "python"),
                           capture_output=True, text=True, timeout=60)
        self.assertEqual((r.returncode, r.stdout), (0, "probe_default\n"), r.stderr)

    def test_a_call_writing_past_a_stats_mirror_is_an_error(self):
        st = L.new(L.amp_contpath_stats)
        self.assertTrue(L.intact(st))
        ctypes.memset(ctypes.addressof(st), 1, ctypes.sizeof(st) + 1)
        self.assertFalse(L.intact(st))
        from ampath.core import _todict
        self.assertRaises(L.StaleMirror, _todict, st)


if __name__ == "__main__":
    unittest.main()
