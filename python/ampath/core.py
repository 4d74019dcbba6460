"""The Python face of libampath: errors, path sets, trivariates, meshes and the pipeline stages.

Ownership: every object here owns the C memory it created and frees it once, in close() (also called by
the context manager and, as a last resort, by __del__); it never frees memory the library lent it.
Threads: ctypes releases the GIL during library calls, so stages run in parallel on different objects;
any number of threads may read one PathSet/Trivariate/Mesh at once (the C API's contract), while a
modification (add, close) takes the object's lock.
"""

import contextlib
import ctypes
import math
import os
import threading

from . import _lib as L
from ._lib import lib

try:  # optional: paths as arrays when NumPy is installed
    import numpy as _np
except ImportError:  # pragma: no cover - depends on the machine
    _np = None

ROLE_OBJECT, ROLE_SUPPORT = 0, 1
_ROLES = {"object": ROLE_OBJECT, "support": ROLE_SUPPORT, ROLE_OBJECT: ROLE_OBJECT, ROLE_SUPPORT: ROLE_SUPPORT}
_ROLE_NAMES = {ROLE_OBJECT: "object", ROLE_SUPPORT: "support"}
STATUS_NAMES = {0: "AMP_OK", -1: "AMP_ERR_ARG", -2: "AMP_ERR_NOMEM", -3: "AMP_ERR_PARSE", -4: "AMP_ERR_GEOMETRY",
                -5: "AMP_ERR_IO", -6: "AMP_ERR_RANGE", -7: "AMP_ERR_LIMIT", -8: "AMP_ERR_STATE",
                -9: "AMP_ERR_UNSUPPORTED", -10: "AMP_ERR_CHECK"}


class Error(Exception):
    """Every failure of the library, and every bad argument value the binding refuses itself (then with
    AMP_ERR_ARG, as the library would); an unknown keyword option is a TypeError, as for any Python call.
    Fields: .status (negative amp_status), .name ("AMP_ERR_PARSE"),
    .reason (amp_strerror: "parse error"), .message (the library's one-line message) and .line."""

    def __init__(self, status, message, line=0):
        self.status = int(status)
        self.name = STATUS_NAMES.get(self.status, "AMP_ERR_%d" % -self.status)
        self.reason = lib.amp_strerror(self.status).decode()
        self.message = message or self.reason
        self.line = line
        super().__init__("%s (%s)" % (self.message, self.name))


def _err():
    e = L.amp_error()
    lib.amp_error_clear(ctypes.byref(e))
    return e


def _check(status, err):
    if status != 0:
        raise Error(status, err.msg.decode("utf-8", "replace"), err.line)


def _fail(message, status=-1):
    raise Error(status, message)


def _b(s):
    return os.fsencode(s) if not isinstance(s, bytes) else s


def _todict(st):
    """A ctypes struct of figures as a dict (vectors as tuples, boxes as {"min", "max"})."""
    if not L.intact(st):
        raise L.stale(type(st), "a call filling it")
    out = {}
    for name, _ in st._fields_:
        v = getattr(st, name)
        if isinstance(v, L.amp_vec3):
            v = (v.x, v.y, v.z)
        elif isinstance(v, L.amp_box3):
            v = {"min": (v.min.x, v.min.y, v.min.z), "max": (v.max.x, v.max.y, v.max.z)}
        elif isinstance(v, ctypes.Array):
            v = list(v)
        out[name] = v
    return out


def _apply(opts, kwargs, what, skip=()):
    """Set fields of an options struct by name: the Python options follow the C struct, so a field added to
    the header is usable as soon as it is added to the mirror in _lib.py."""
    names = {n for n, _ in opts._fields_} - set(skip) - {"progress", "progress_user"}
    for k, v in kwargs.items():
        if k not in names:
            raise TypeError("%s: unknown option %r (known: %s)" % (what, k, ", ".join(sorted(names))))
        setattr(opts, k, v)


class _Progress:
    """A Python callable as the C progress callback; the ctypes object lives as long as this one (the
    call), and an exception raised by the callable is re-raised after the call returns."""

    def __init__(self, fn):
        self.fn, self.exc = fn, None
        self.c = L.PROGRESS_FN(self._call) if fn else L.PROGRESS_FN()

    def _call(self, _user, fraction):
        if self.exc is None:
            try:
                self.fn(fraction)
            except BaseException as e:  # noqa: B902 - kept and re-raised in the caller's frame
                self.exc = e

    def done(self):
        if self.exc is not None:
            raise self.exc


def _head(z_offs, theta_deg):
    h = L.amp_head(z_offs, theta_deg * math.pi / 180.0)
    err = _err()
    _check(lib.amp_head_validate(ctypes.byref(h), ctypes.byref(err)), err)
    return h


class _Owner:
    """Common close/context-manager/__del__ logic for objects that own C memory. A library call reading
    the object holds it (_using): close() from another thread then waits for the call to return instead
    of freeing memory under it (ctypes releases the GIL during the call)."""

    def __init__(self):
        self._lock = threading.RLock()
        self._idle = threading.Condition(self._lock)
        self._users = 0
        self._open = True

    @contextlib.contextmanager
    def _using(self):
        with self._lock:
            self._live()
            self._users += 1
        try:
            yield self
        finally:
            with self._lock:
                self._users -= 1
                if self._users == 0:
                    self._idle.notify_all()

    def close(self):
        with self._lock:
            while self._users:
                self._idle.wait()
            if self._open:
                self._open = False
                self._release()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        # at interpreter exit the module globals may be gone: then the process frees everything anyway
        try:
            self.close()
        except Exception:  # pragma: no cover
            pass

    def _live(self):
        if not self._open:
            _fail("%s is closed" % type(self).__name__, -8)


# ---------------------------------------------------------------- paths


class Path:
    """One path (a copy): role ("object"/"support"), bead height h (0 = tube) and points (x, y, z, r)."""

    __slots__ = ("role", "h", "points")

    def __init__(self, role, h, points):
        self.role, self.h, self.points = role, h, points

    def __len__(self):
        return len(self.points)

    def array(self):
        """The points as an (n, 4) NumPy array (needs NumPy)."""
        if _np is None:
            raise ImportError("NumPy is not installed")
        return _np.asarray(self.points, dtype=float).reshape(-1, 4)

    def __repr__(self):
        return "Path(%s, %d points%s)" % (self.role, len(self.points), ", h=%g" % self.h if self.h else "")


class PathSet(_Owner):
    """Paths in print order (an amp_pathset, the `.amp` file in memory).

    ps = PathSet(); ps.add([(0, 0, 0.2), (10, 0, 0.2)], radius=0.25, h=0.2)
    ps = PathSet.read("job.amp"); ps[0].points; ps.write("out.amp"); text = ps.to_amp()
    Results of the pipeline stages carry their figures in .stats (a dict).
    """

    def __init__(self):
        super().__init__()
        self._ps = L.amp_pathset()
        lib.amp_pathset_init(ctypes.byref(self._ps), None)
        self.stats = {}
        self.source = None  # the file it was read from (ampath.check reads the eps `ampath cover` noted there)
        # the tool's `# ampath ...` history lines, newest first: read from a file's header, set by the stages,
        # written back by to_amp()/write() (so `ampath check` finds the eps `cover` or `field` noted)
        self.history = []

    def _release(self):
        lib.amp_pathset_free(ctypes.byref(self._ps))

    @property
    def _ref(self):
        self._live()
        return ctypes.byref(self._ps)

    @classmethod
    def read(cls, filename, progress=None):
        """The paths of a .amp file; @progress (a callable taking the fraction read) hears of the parse."""
        ps, err = cls(), _err()
        if progress is not None and "amp_pathset_read_file_progress" not in L.MISSING:
            pr = _Progress(progress)
            st = lib.amp_pathset_read_file_progress(ps._ref, _b(filename), pr.c, None, ctypes.byref(err))
            if st:
                ps.close()
            _check(st, err)
            pr.done()
        else:
            st = lib.amp_pathset_read_file(ps._ref, _b(filename), ctypes.byref(err))
            if st:
                ps.close()
            _check(st, err)
        ps.source = os.fsdecode(filename)
        try:
            with open(filename, "rb") as f:
                ps.history = _history_of(f.read(65536).decode("utf-8", "replace"))
        except OSError:
            pass
        return ps

    @classmethod
    def parse(cls, text):
        data = text.encode() if isinstance(text, str) else bytes(text)
        ps, err = cls(), _err()
        st = lib.amp_pathset_parse(ps._ref, data, len(data), ctypes.byref(err))
        if st:
            ps.close()
        _check(st, err)
        ps.history = _history_of(data[:65536].decode("utf-8", "replace"))
        return ps

    def add(self, points, role="object", radius=None, h=0.0):
        """Append a path. @points: a sequence (or NumPy array) of (x, y, z, r), or of (x, y, z) with @radius.
        Waits for library calls reading this set in other threads (the arrays may move)."""
        if role not in _ROLES:
            _fail("role must be 'object' or 'support'")
        if _np is not None and isinstance(points, _np.ndarray):
            points = points.tolist()
        with self._lock:
            while self._users:
                self._idle.wait()
            err = _err()
            _check(lib.amp_pathset_begin(self._ref, _ROLES[role], ctypes.byref(err)), err)
            for p in points:
                if len(p) == 3:
                    if radius is None:
                        _fail("points without a radius need radius=")
                    x, y, z, r = p[0], p[1], p[2], radius
                else:
                    x, y, z, r = p
                _check(lib.amp_pathset_push(self._ref, L.amp_vec3(x, y, z), r, ctypes.byref(err)), err)
            if h:
                _check(lib.amp_pathset_set_height(self._ref, h, ctypes.byref(err)), err)
        return self

    def extend(self, other):
        """Append copies of all paths of @other."""
        if other is self:
            _fail("extend: a set cannot be appended to itself")
        with self._lock:
            while self._users:
                self._idle.wait()
            with other._using():
                err = _err()
                _check(lib.amp_pathset_append(self._ref, other._ref, ctypes.byref(err)), err)
        return self

    def __len__(self):
        self._live()
        return self._ps.npaths

    def __getitem__(self, i):
        self._live()
        n = self._ps.npaths
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError("path index out of range")
        p = self._ps.paths[i]
        v = self._ps.verts
        pts = [(v[k].p.x, v[k].p.y, v[k].p.z, v[k].r) for k in range(p.first, p.first + p.n)]
        return Path(_ROLE_NAMES.get(p.role, p.role), p.h, pts)

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def array(self):
        """All vertices as an (n, 4) NumPy array of x, y, z, r (needs NumPy; one copy, no Python loop)."""
        if _np is None:
            raise ImportError("NumPy is not installed")
        with self._using():  # add() in another thread waits: the vertex array does not move under the copy
            n = self._ps.nverts
            if n == 0:
                return _np.zeros((0, 4))
            buf = (ctypes.c_double * (4 * n)).from_address(ctypes.addressof(self._ps.verts.contents))
            return _np.array(buf, dtype=float).reshape(n, 4)

    @property
    def vertex_count(self):
        self._live()
        return self._ps.nverts

    def length(self, role=None):
        """Total length (mm) of the paths with @role ("object", "support"; None = all)."""
        return lib.amp_pathset_length(self._ref, -1 if role is None else _ROLES[role])

    def volume(self, role=None):
        """Deposited bead volume Σ A·L (mm³, docs/interfaces.md §5) of the paths with @role (None = all)."""
        return lib.amp_pathset_volume(self._ref, -1 if role is None else _ROLES[role])

    def bbox(self):
        b = lib.amp_pathset_bbox(self._ref)
        return {"min": (b.min.x, b.min.y, b.min.z), "max": (b.max.x, b.max.y, b.max.z)}

    def _comment(self, comment):
        return "\n".join(self.history) if comment is None and self.history else comment

    def to_amp(self, comment=None):
        """The `.amp` text (docs/interfaces.md §3) as a str; @comment (default: the history lines, as the tool
        writes them) becomes `# ` lines after the header."""
        comment = self._comment(comment)
        with self._using():
            return _to_buf(lambda sink, buf, err: lib.amp_pathset_write(
                self._ref, None if comment is None else comment.encode(), sink, buf, err)).decode()

    def as_written(self):
        """A new PathSet as it would be read back from its `.amp` file (coordinates rounded to the file's
        10 significant digits): what the next `ampath` command sees, so that a chain of stages reproduces
        the tool's chain bit for bit."""
        return PathSet.parse(self.to_amp())

    def write(self, filename, comment=None):
        """Write the `.amp` file (replaced atomically); @comment as for to_amp()."""
        err = _err()
        comment = self._comment(comment)
        with self._using():
            _check(lib.amp_pathset_write_file(self._ref, _b(filename),
                                              None if comment is None else comment.encode(), ctypes.byref(err)),
                   err)

    def __repr__(self):
        if not self._open:
            return "PathSet(closed)"
        return "PathSet(%d paths, %d vertices)" % (self._ps.npaths, self._ps.nverts)


@contextlib.contextmanager
def _hold(*objs):
    """Hold every owned object among @objs for the duration of a library call."""
    with contextlib.ExitStack() as stack:
        for o in objs:
            if isinstance(o, _Owner):
                stack.enter_context(o._using())
        yield


def _write_bytes(output, data):
    """Write @data to the file @output through the library's one safe writer (amp_out: a temporary beside it,
    renamed over it; a failure leaves the old file as it was)."""
    f, err = L.amp_out(), _err()
    _check(lib.amp_out_open(ctypes.byref(f), os.fsencode(output), ctypes.byref(err)), err)
    if lib.amp_out_sink(ctypes.byref(f), data, len(data)) != 0:
        lib.amp_out_abort(ctypes.byref(f))
        err.msg = ("%s: %s" % (f.target.decode(errors="replace"), os.strerror(f.werr))).encode()[:199]
        _check(-5, err)
    _check(lib.amp_out_commit(ctypes.byref(f), ctypes.byref(err)), err)


def _history_of(text):
    """The `# ampath ...` lines of a `.amp` header (before its first path), without the `# `, at most 16."""
    out = []
    for line in text.split("\n")[1:]:
        if not line.startswith("#"):
            break
        if line.startswith("# ampath ") and len(out) < 16:
            out.append(line[2:].rstrip("\r"))
    return out


def _derive(out, line, inp):
    """@out's history: the stage's own line, then @inp's (the tool's cli_save_derived)."""
    out.history = [line] + [h for h in getattr(inp, "history", []) if h != line][:15]


def _to_buf(write):
    """Run a library writer into an amp_buf and return the bytes (the buffer is always freed)."""
    buf, err = L.amp_buf(), _err()
    lib.amp_buf_init(ctypes.byref(buf), None)
    try:
        _check(write(L.BUF_SINK, ctypes.cast(ctypes.byref(buf), ctypes.c_void_p), ctypes.byref(err)), err)
        return ctypes.string_at(buf.data, buf.len) if buf.len else b""
    finally:
        lib.amp_buf_free(ctypes.byref(buf))


# ---------------------------------------------------------------- trivariates and meshes


def trivariate_names():
    names, p, i = [], lib.amp_trivariate_model_names(), 0
    while p[i]:
        names.append(p[i].decode())
        i += 1
    return names


def mesh_names():
    return [lib.amp_mesh_model_name(i).decode() for i in range(lib.amp_mesh_model_count())]


class Trivariate(_Owner):
    """A trivariate B-spline volume (amp_spline with dim 3)."""

    def __init__(self):
        super().__init__()
        self._s = L.amp_spline()
        lib.amp_spline_init(ctypes.byref(self._s))
        self.name = None  # the built-in name or file it came from (the tool's cover line names it)

    def _release(self):
        lib.amp_spline_free(ctypes.byref(self._s))

    @property
    def _ref(self):
        self._live()
        return ctypes.byref(self._s)

    @classmethod
    def model(cls, name):
        """Built-in trivariate (helix, torus-quarter, vase)."""
        t, err = cls(), _err()
        _check(lib.amp_trivariate_model(_b(name), None, t._ref, ctypes.byref(err)), err)
        t.name = name
        return t

    @classmethod
    def _take_first(cls, st, lst, n, err, what):
        _check(st, err)
        try:
            for i in range(n.value):
                if lst[i].dim == 3:
                    t = cls()
                    # copy the struct: ownership of its arrays moves to t, the list entry is emptied
                    ctypes.memmove(ctypes.byref(t._s), ctypes.byref(lst[i]), ctypes.sizeof(L.amp_spline))
                    lib.amp_spline_init(ctypes.byref(lst[i]))
                    return t
            _fail("%s: no trivariate in the file" % what, -3)
        finally:
            lib.amp_spline_list_free(None, lst, n.value)

    @classmethod
    def load(cls, what):
        """The first trivariate of a `.spl` file, or a built-in model by name (as the tool does)."""
        if what in trivariate_names():
            return cls.model(what)
        lst, n, err = ctypes.POINTER(L.amp_spline)(), ctypes.c_size_t(), _err()
        st = lib.amp_spline_read_file(_b(what), None, ctypes.byref(lst), ctypes.byref(n), ctypes.byref(err))
        t = cls._take_first(st, lst, n, err, what)
        t.name = os.fsdecode(what)
        return t

    @classmethod
    def parse(cls, text):
        data = text.encode() if isinstance(text, str) else bytes(text)
        lst, n, err = ctypes.POINTER(L.amp_spline)(), ctypes.c_size_t(), _err()
        st = lib.amp_spline_parse(data, len(data), None, ctypes.byref(lst), ctypes.byref(n), ctypes.byref(err))
        return cls._take_first(st, lst, n, err, "text")

    def to_spl(self):
        return _to_buf(lambda sink, buf, err: lib.amp_spline_write(self._ref, 1, sink, buf, err)).decode()

    def write(self, filename):
        """Write the `.spl` file (replaced atomically: a failure leaves the old file as it was)."""
        _write_bytes(filename, self.to_spl().encode())

    def eval(self, u, v, w):
        par, out, err = (ctypes.c_double * 3)(u, v, w), L.amp_vec3(), _err()
        _check(lib.amp_spline_eval(self._ref, par, ctypes.byref(out), ctypes.byref(err)), err)
        return (out.x, out.y, out.z)

    def volume(self):
        return lib.amp_trivariate_volume(self._ref)

    def bbox(self):
        b = lib.amp_spline_cp_bbox(self._ref)
        return {"min": (b.min.x, b.min.y, b.min.z), "max": (b.max.x, b.max.y, b.max.z)}


class Mesh(_Owner):
    """A triangle mesh (amp_mesh) with its BVH built on first use (for support and field)."""

    def __init__(self):
        super().__init__()
        self._m = L.amp_mesh()
        lib.amp_mesh_init(ctypes.byref(self._m), None)
        self._bvh = ctypes.c_void_p()
        self.stl_stats = {}

    def _release(self):
        if self._bvh:
            lib.amp_bvh_free(self._bvh)
            self._bvh = ctypes.c_void_p()
        lib.amp_mesh_free(ctypes.byref(self._m))

    @property
    def _ref(self):
        self._live()
        return ctypes.byref(self._m)

    def _changed(self):
        if self._bvh:
            lib.amp_bvh_free(self._bvh)
            self._bvh = ctypes.c_void_p()

    def bvh(self):
        with self._lock:
            if not self._bvh:
                err = _err()
                _check(lib.amp_bvh_build(ctypes.byref(self._bvh), self._ref, ctypes.byref(err)), err)
            return self._bvh

    @classmethod
    def model(cls, name, tol=0.0):
        """Built-in mesh (helix, twisted-bridge, crocodile-like), or the tessellated boundary of the built-in
        trivariate of that name (as `ampath model NAME -o F.stl`)."""
        m, err = cls(), _err()
        st = lib.amp_mesh_model(_b(name), tol, m._ref, ctypes.byref(err))
        if st != 0 and name in trivariate_names():
            m.close()
            with Trivariate.model(name) as t:
                return cls.from_trivariate(t)
        if st:
            m.close()
        _check(st, err)
        return m

    @classmethod
    def load(cls, filename):
        """Read an STL file (binary or ASCII); .stl_stats says what the reader saw."""
        m, err, ss = cls(), _err(), L.new(L.amp_stl_stats)
        st = lib.amp_mesh_read_stl_file_ex(m._ref, _b(filename), ctypes.byref(ss), ctypes.byref(err))
        if st:
            m.close()
        _check(st, err)
        m.stl_stats = _todict(ss)
        return m

    @classmethod
    def from_stl_bytes(cls, data):
        m, err, ss = cls(), _err(), L.new(L.amp_stl_stats)
        data = bytes(data)
        st = lib.amp_mesh_read_stl_ex(m._ref, data, len(data), ctypes.byref(ss), ctypes.byref(err))
        if st:
            m.close()
        _check(st, err)
        m.stl_stats = _todict(ss)
        return m

    @classmethod
    def from_trivariate(cls, t, res=0):
        m, err = cls(), _err()
        st = lib.amp_mesh_from_trivariate(m._ref, t._ref, res, ctypes.byref(err))
        if st:
            m.close()
        _check(st, err)
        return m

    def to_stl(self, binary=True):
        return _to_buf(lambda sink, buf, err: lib.amp_mesh_write_stl(self._ref, 1 if binary else 0, sink, buf, err))

    def write(self, filename, binary=True):
        err = _err()
        _check(lib.amp_mesh_write_stl_file(self._ref, _b(filename), 1 if binary else 0, ctypes.byref(err)), err)

    def orient(self):
        """Make the triangle orientation consistent (outward); returns the number of triangles flipped."""
        with self._lock:
            while self._users:  # a call reading the mesh (or its BVH) finishes first
                self._idle.wait()
            n, err = ctypes.c_size_t(), _err()
            _check(lib.amp_mesh_orient(self._ref, ctypes.byref(n), ctypes.byref(err)), err)
            if n.value:
                self._changed()
            return n.value

    @property
    def triangles(self):
        return self._m.ntris

    @property
    def vertices(self):
        return self._m.nverts

    def volume(self):
        return lib.amp_mesh_volume(self._ref)

    def bbox(self):
        b = lib.amp_mesh_bbox(self._ref)
        return {"min": (b.min.x, b.min.y, b.min.z), "max": (b.max.x, b.max.y, b.max.z)}
