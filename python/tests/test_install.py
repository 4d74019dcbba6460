"""`pip install ./python` works offline (no index: the build backend needs nothing), into a target
directory and into a fresh virtual environment, without writing into the source tree; the installed
package finds the library through AMPATH_LIBRARY or pkg-config (the ampath.pc of `make install`), or says
clearly that it cannot."""

import os
import shutil
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


def tree(path):
    return sorted(os.path.relpath(os.path.join(d, f), path) for d, _, fs in os.walk(path) for f in fs
                  if "__pycache__" not in d)


def venv_ok():
    import importlib.util
    return all(importlib.util.find_spec(m) is not None for m in ("venv", "ensurepip"))


@unittest.skipUnless(has_pip() and venv_ok(), "no pip or venv (ensurepip) in this Python")
class Venv(TmpCase):
    def test_fresh_venv_offline_install_finds_the_library_through_pkg_config(self):
        src = os.path.join(ROOT, "python")
        before = tree(src)
        venv = self.p("venv")
        subprocess.run([sys.executable, "-m", "venv", venv], check=True, capture_output=True, timeout=600)
        py = os.path.join(venv, "bin", "python")
        env = {k: v for k, v in os.environ.items() if k not in ("AMPATH_LIBRARY", "PYTHONPATH", "PKG_CONFIG_PATH")}
        env.update(PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
        r = subprocess.run([py, "-m", "pip", "install", "--no-index", src], capture_output=True, text=True, env=env,
                           timeout=600, cwd=self.tmp)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(tree(src), before, "pip install wrote into the source tree")
        code = "import ampath; print(ampath.__file__); print(ampath.LIBRARY_PATH); print(ampath.printer_names()[0])"
        # nothing tells it where the library is (and none is installed system-wide): a clear ImportError
        import ctypes.util
        if ctypes.util.find_library("ampath") is None:
            r = subprocess.run([py, "-c", code], capture_output=True, text=True, env=env, cwd=self.tmp)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn("libampath.so not found", r.stderr)
        # an installed library as `make install` lays it out: PREFIX/lib/libampath.so and its ampath.pc
        if not shutil.which("pkg-config"):
            self.skipTest("pkg-config is not installed")
        libdir = os.path.join(self.tmp, "prefix", "lib")
        os.makedirs(os.path.join(libdir, "pkgconfig"))
        os.symlink(L.LIBRARY_PATH, os.path.join(libdir, "libampath.so"))
        with open(os.path.join(libdir, "pkgconfig", "ampath.pc"), "w") as f:
            f.write("prefix=%s\nlibdir=%s\n\nName: ampath\nDescription: test\nVersion: 0.1.0\nLibs: -L${libdir} "
                    "-lampath\n" % (os.path.dirname(libdir), libdir))
        env["PKG_CONFIG_PATH"] = os.path.join(libdir, "pkgconfig")
        r = subprocess.run([py, "-c", code], capture_output=True, text=True, env=env, cwd=self.tmp)
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertTrue(lines[0].startswith(venv), lines)
        self.assertEqual(lines[1:], [os.path.join(libdir, "libampath.so"), "generic"])


if __name__ == "__main__":
    unittest.main()
