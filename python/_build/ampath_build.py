"""A PEP 517 build backend in the standard library only, so that `pip install ./python` works offline:
pip's isolated build environment then needs nothing from an index (a `setuptools` requirement would have
to be downloaded there). The package is pure Python; the "build" zips python/ampath/ into a wheel.
PEP 660 editable installs (`pip install -e ./python`) put a .pth file pointing at this directory."""

import base64
import hashlib
import os
import zipfile

NAME, VERSION = "ampath", "0.1.0"
HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIST = "%s-%s.dist-info" % (NAME, VERSION)
TAG = "py3-none-any"
SUMMARY = "Python binding of libampath (ctypes): volumetric covering, continuous tool paths, G-code, bridge client"


def _metadata():
    with open(os.path.join(HERE, "README.md")) as f:
        readme = f.read()
    return ("Metadata-Version: 2.1\nName: %s\nVersion: %s\nSummary: %s\nRequires-Python: >=3.7\n"
            "Provides-Extra: numpy\nRequires-Dist: numpy; extra == \"numpy\"\n"
            "Description-Content-Type: text/markdown\n\n%s" % (NAME, VERSION, SUMMARY, readme))


def _wheel(directory, files):
    name = "%s-%s-%s.whl" % (NAME, VERSION, TAG)
    files = list(files) + [(DIST + "/METADATA", _metadata().encode()),
                           (DIST + "/WHEEL", ("Wheel-Version: 1.0\nGenerator: ampath_build\nRoot-Is-Purelib: true\n"
                                               "Tag: %s\n" % TAG).encode())]
    record = []
    with zipfile.ZipFile(os.path.join(directory, name), "w", zipfile.ZIP_DEFLATED) as z:
        for arc, data in files:
            z.writestr(arc, data)
            digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            record.append("%s,sha256=%s,%d" % (arc, digest, len(data)))
        record.append(DIST + "/RECORD,,")
        z.writestr(DIST + "/RECORD", "\n".join(record) + "\n")
    return name


def _sources():
    pkg = os.path.join(HERE, NAME)
    for f in sorted(os.listdir(pkg)):
        if f.endswith(".py"):
            with open(os.path.join(pkg, f), "rb") as fh:
                yield "%s/%s" % (NAME, f), fh.read()


def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_editable(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    return _wheel(wheel_directory, _sources())


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    return _wheel(wheel_directory, [("ampath_editable.pth", (HERE + "\n").encode())])


def build_sdist(sdist_directory, config_settings=None):
    import tarfile
    name = "%s-%s" % (NAME, VERSION)
    path = os.path.join(sdist_directory, name + ".tar.gz")
    with tarfile.open(path, "w:gz") as t:
        for rel in ("pyproject.toml", "README.md", "_build/ampath_build.py"):
            t.add(os.path.join(HERE, rel), arcname="%s/%s" % (name, rel))
        for arc, _ in _sources():
            t.add(os.path.join(HERE, arc), arcname="%s/%s" % (name, arc))
    return os.path.basename(path)
