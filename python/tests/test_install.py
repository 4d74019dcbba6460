"""`pip install ./python` works offline (no index: the build backend needs nothing), and the installed
package finds the library through AMPATH_LIBRARY, or says clearly that it cannot."""

import os
import subprocess
import sys
import unittest

from amptest import ROOT, TmpCase

from ampath import _lib as L


def has_pip():
    return subprocess.run([sys.executable, "-m", "pip", "--version"], capture_output=True).returncode == 0


@unittest.skipUnless(has_pip(), "pip is not installed")
class Install(TmpCase):
    def test_offline_pip_install_then_import_from_anywhere(self):
        target = self.p("site")
        env = dict(os.environ, PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
        r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-index", "--target", target,
                            os.path.join(ROOT, "python")], capture_output=True, text=True, env=env, timeout=600)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertTrue(os.path.exists(os.path.join(target, "ampath", "__init__.py")))
        code = "import ampath; print(ampath.__file__); print(ampath.LIBRARY_PATH); print(ampath.printer_names()[0])"
        env = dict(os.environ, PYTHONPATH=target, AMPATH_LIBRARY=L.LIBRARY_PATH)
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=self.tmp)
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertTrue(lines[0].startswith(target), lines)
        self.assertEqual(lines[1:], [L.LIBRARY_PATH, "generic"])
        # a wrong AMPATH_LIBRARY is an ImportError that names what was tried
        env["AMPATH_LIBRARY"] = self.p("nowhere/libampath.so")
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=self.tmp)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("ImportError: libampath.so not found", r.stderr)
        self.assertIn("nowhere/libampath.so", r.stderr)


if __name__ == "__main__":
    unittest.main()
