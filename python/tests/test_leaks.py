"""Reference counts and leaks over 1,000 pipeline runs on small inputs: the bytes malloc has handed out
(glibc's mallinfo2, all arenas: the C memory of the library), the resident set size and tracemalloc
(Python memory) stay bounded, error paths included; the same measure does see a leak of one path set per
run (the self-test below), so the bound is not vacuous; without amp_hold_report_free in ampath.check the
first test sees about 1 MB (measured once by hand). RSS alone would not do: freed heap is reused,
so a leak can hide in it."""

import ctypes
import gc
import os
import tracemalloc
import unittest

from amptest import ampath

RUNS = 1000
BOUND = 256 << 10  # bytes of malloc growth allowed over the runs after warm-up (caches, lists)
PAGE = os.sysconf("SC_PAGE_SIZE")


def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE


class _mallinfo2(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks",
                                               "fsmblks", "uordblks", "fordblks", "keepcost")]


try:
    _libc = ctypes.CDLL(None)
    _libc.mallinfo2.restype = _mallinfo2
except (OSError, AttributeError):
    _libc = None


def _gomp():
    try:
        g = ctypes.CDLL("libgomp.so.1", mode=os.RTLD_NOLOAD)  # only if the library brought it in
        return g if hasattr(g, "omp_set_num_threads") else None
    except OSError:
        return None


class one_thread:
    """OpenMP on one thread while measuring: waking a team for every tiny parallel region costs
    milliseconds per call on a loaded machine (the runs here are about memory, not threads)."""

    def __enter__(self):
        self.g = _gomp()
        if self.g:
            self.n = self.g.omp_get_max_threads()
            self.g.omp_set_num_threads(1)

    def __exit__(self, *exc):
        if self.g:
            self.g.omp_set_num_threads(self.n)


def malloc_in_use():
    """Bytes in use from malloc, over all arenas, mmapped blocks included."""
    m = _libc.mallinfo2()
    return m.uordblks + m.hblkhd


def zigzag(n=24, z=0.2):
    return [(0.5 * i, 3.0 * (i % 2), z) for i in range(n)]


MESH = None  # a small mesh for the field calls, made once


def one_run(leak=None):
    with ampath.PathSet() as ps:
        ps.add(zigzag(), radius=0.3, h=0.2)
        ps.add(zigzag(z=0.4), radius=0.3, h=0.2)
        with ampath.order(ps) as o, ampath.mdr(o, nominal=0.3, fragment=1.0) as m:
            text = ampath.gcode(m, printer="generic").text
            # the checkers (the support report's arrays are the library's: freed after every call)
            assert ampath.check(m, support=True, max_gap=0.5)["support"]["ran"]
            with ampath.PathSet() as air:  # 64 paths in the air: a report with a list of 64 (512 bytes)
                for k in range(64):
                    air.add([(0, 2 * k, 5), (1, 2 * k, 5)], radius=0.3)
                assert ampath.check(air, support=True, skip=("gouge",))["support"]["unheld_paths"] == 64
            try:
                ampath.gcode(m, place=(1e4, 0))  # refused: the error path must not leak either
            except ampath.Error:
                pass
            try:
                ampath.field(MESH, "sweep", along=[(0, 0, 0)])  # refused by amp_field_sweep
            except ampath.Error:
                pass
            if leak is not None:
                leak(m)
    return len(text)


@unittest.skipUnless(os.path.exists("/proc/self/statm") and _libc is not None, "needs /proc and glibc >= 2.33")
class Leaks(unittest.TestCase):
    def measure(self, runs, leak=None):
        with one_thread():
            return self._measure(runs, leak)

    @classmethod
    def setUpClass(cls):
        global MESH
        MESH = ampath.Mesh.model("twisted-bridge")

    @classmethod
    def tearDownClass(cls):
        MESH.close()

    def _measure(self, runs, leak=None):
        for _ in range(20):  # warm-up: allocator arenas, caches
            one_run()
        gc.collect()
        tracemalloc.start()
        r0, m0, (p0, _) = rss(), malloc_in_use(), tracemalloc.get_traced_memory()
        for _ in range(runs):
            one_run(leak)
        gc.collect()
        p1, _ = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        return malloc_in_use() - m0, rss() - r0, p1 - p0

    def test_a_thousand_pipeline_runs_stay_bounded(self):
        before = len(gc.get_objects())
        c_growth, rss_growth, py_growth = self.measure(RUNS)
        self.assertLess(c_growth, BOUND, "malloc in use grew by %d bytes over %d runs" % (c_growth, RUNS))
        self.assertLess(rss_growth, 8 << 20, "resident set grew by %d bytes over %d runs" % (rss_growth, RUNS))
        self.assertLess(py_growth, 256 << 10, "Python heap grew by %d bytes" % py_growth)
        self.assertLess(len(gc.get_objects()) - before, 1000)

    def test_the_measure_sees_a_leaked_path_set_per_run(self):
        from ampath import _lib as L
        leaked = []

        def leak(m):  # a copy that is never freed: what a missing amp_pathset_free would do
            ps = L.amp_pathset()
            L.lib.amp_pathset_init(ctypes.byref(ps), None)
            err = L.amp_error()
            L.lib.amp_pathset_append(ctypes.byref(ps), m._ref, ctypes.byref(err))
            leaked.append(ctypes.addressof(ps.verts.contents))  # keep only the address: the memory stays lost
        c_growth, _, _ = self.measure(100, leak)  # 100 x a few KB
        self.assertGreater(c_growth, BOUND, "a leak of %d path sets went unseen" % len(leaked))


if __name__ == "__main__":
    unittest.main()
