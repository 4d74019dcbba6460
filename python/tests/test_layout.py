"""The ctypes mirrors of the C structs (ampath/_lib.py STRUCTS) have the C layout: every field's offset and
every struct's size compared with what the C compiler says for include/ampath/*.h. After a header change
this test names the struct and field to update in _lib.py. Needs a C compiler (make check has one)."""

import ctypes
import os
import shutil
import subprocess
import unittest

from amptest import ROOT, TmpCase

from ampath import _lib as L

CC = os.environ.get("CC", "cc")


@unittest.skipUnless(shutil.which(CC), "no C compiler")
class Layout(TmpCase):
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


if __name__ == "__main__":
    unittest.main()
