"""The Python API itself: paths as sequences (and NumPy arrays), figures, progress callbacks, threads,
ownership (close, context managers)."""

import threading
import unittest

from amptest import TmpCase, ampath, read, strip_comments, tool

try:
    import numpy
except ImportError:
    numpy = None


def square(z=0.2, r=0.25, n=4):
    return [(10 * (i % 2), 10 * (i // 2 % 2), z, r) for i in range(n)]


class Paths(TmpCase):
    def test_paths_from_sequences_round_trip_through_amp_text(self):
        with ampath.PathSet() as ps:
            ps.add([(0, 0, 0.2), (10, 0, 0.2), (10, 5, 0.2)], radius=0.25, h=0.2)
            ps.add([(0, 0, 1, 0.5), (0, 0, 2, 0.5)], role="support")
            self.assertEqual(len(ps), 2)
            self.assertEqual(ps.vertex_count, 5)
            self.assertEqual(ps[0].role, "object")
            self.assertEqual(ps[0].h, 0.2)
            self.assertEqual(ps[-1].role, "support")
            self.assertEqual(ps[1].points, [(0, 0, 1, 0.5), (0, 0, 2, 0.5)])
            self.assertAlmostEqual(ps.length(), 16.0)  # 10 + 5 + 1
            self.assertAlmostEqual(ps.length("support"), 1.0)
            text = ps.to_amp(comment="made in Python")
            self.assertTrue(text.startswith("ampath-paths 1\n# made in Python\n"))
            self.assertIn("path object 3 0.2\n", text)
            ps.write(self.p("a.amp"))
            with ampath.PathSet.read(self.p("a.amp")) as back:
                self.assertEqual([p.points for p in back], [p.points for p in ps])
            with self.assertRaises(IndexError):
                ps[2]
            with self.assertRaises(ampath.Error) as cm:  # the library refuses a negative radius
                ps.add([(0, 0, 0, -1)])
            self.assertEqual(cm.exception.name, "AMP_ERR_ARG")

    @unittest.skipIf(numpy is None, "NumPy is not installed (optional)")
    def test_paths_as_numpy_arrays(self):
        pts = numpy.array(square())
        with ampath.PathSet() as ps:
            ps.add(pts)
            ps.add(pts[:, :3] + 1, radius=0.3)
            a = ps.array()
            self.assertEqual(a.shape, (8, 4))
            self.assertTrue((a[:4] == pts).all())
            self.assertTrue((ps[1].array()[:, 3] == 0.3).all())
            self.assertEqual(ps[0].points, [tuple(map(float, p)) for p in square()])
            # a NumPy spine for the sweep field, as a sequence would be
            with ampath.Mesh.model("crocodile-like") as m:
                spine = [(14, 2, 13), (16, 6, 9), (19, 15, 6), (17, 17, -1)]
                with ampath.field(m, "sweep", along=numpy.array(spine), side=7, spacing=3) as a, \
                        ampath.field(m, "sweep", along=spine, side=7, spacing=3) as b:
                    self.assertEqual(a.to_amp(), b.to_amp())
                    self.assertEqual(a.array().shape, (a.vertex_count, 4))

    def test_without_numpy_sequences_work_and_arrays_say_numpy_is_missing(self):
        code = ("import sys; sys.modules['numpy'] = None\n"  # as if NumPy were not installed
                "import ampath\n"
                "ps = ampath.PathSet().add([(0, 0, 0.2), (10, 0, 0.2)], radius=0.25)\n"
                "print(ps[0].points)\n"
                "for a in (ps.array, ps[0].array):\n"
                "    try:\n"
                "        a()\n"
                "    except ImportError as e:\n"
                "        print(e)\n")
        import os
        import subprocess
        import sys
        from amptest import HERE
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                           env=dict(os.environ, PYTHONPATH=os.path.join(HERE, "..")))
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.splitlines(), ["[(0.0, 0.0, 0.2, 0.25), (10.0, 0.0, 0.2, 0.25)]",
                                                 "NumPy is not installed", "NumPy is not installed"])

    def test_closed_objects_refuse_use_and_close_twice_is_harmless(self):
        ps = ampath.PathSet().add(square())
        ps.close()
        ps.close()
        with self.assertRaises(ampath.Error) as cm:
            len(ps)
        self.assertEqual(cm.exception.name, "AMP_ERR_STATE")
        with ampath.Mesh.model("helix") as m:
            self.assertGreater(m.triangles, 1000)
        self.assertRaises(ampath.Error, m.volume)

    def test_models_and_files_match_the_tool(self):
        tool("model", "torus-quarter", "-o", self.p("t.spl"))
        with ampath.Trivariate.load(self.p("t.spl")) as t, ampath.Trivariate.load("torus-quarter") as u:
            self.assertEqual(t.to_spl(), u.to_spl())
            self.assertEqual(t.to_spl().encode(), read(self.p("t.spl")))
            self.assertGreater(t.volume(), 0)
            x, y, z = t.eval(0.5, 0.5, 0.5)
            self.assertTrue(abs(x) + abs(y) > 10)
        tool("model", "twisted-bridge", "-o", self.p("b.stl"))
        with ampath.Mesh.load(self.p("b.stl")) as m, ampath.Mesh.model("twisted-bridge") as b:
            self.assertEqual(m.stl_stats["binary"], 1)
            self.assertEqual(m.triangles, b.triangles)
            self.assertEqual(b.to_stl(), read(self.p("b.stl")))


class Stages(TmpCase):
    def test_progress_callbacks_report_rising_fractions(self):
        seen = []
        with ampath.Trivariate.model("helix") as v:
            with ampath.cover(v, eps=3, progress=seen.append) as ps:
                self.assertGreater(len(ps), 0)
                self.assertGreater(ps.stats["curves"], 0)
                self.assertEqual(ps.stats["dir"], "v")  # chosen: curves along the helix, not round its disc
        self.assertGreater(len(seen), 2)
        self.assertEqual(seen, sorted(seen))
        self.assertTrue(0 <= seen[0] and seen[-1] <= 1.0)

    def test_an_exception_in_a_progress_callback_reaches_the_caller(self):
        def boom(_f):
            raise KeyError("stop")
        with ampath.Trivariate.model("helix") as v, self.assertRaises(KeyError):
            ampath.cover(v, eps=3, progress=boom)

    def test_check_returns_figures_and_fails_on_a_gouging_order(self):
        with ampath.Trivariate.model("helix") as v, ampath.cover(v, eps=3) as ps:
            with ampath.order(ps) as good:
                res = ampath.check(good, trivariate=v, eps=3, samples=2000)
                self.assertTrue(res["ok"], res)
                self.assertTrue(res["gouge"]["ok"])
                self.assertLessEqual(res["coverage"]["coverage_gap_mm"], 3)
        # a high path printed first, then one right under it: the head gouges the first
        with ampath.PathSet() as bad:
            bad.add([(0, 0, 5), (10, 0, 5)], radius=0.5)
            bad.add([(0, 0, 1), (10, 0, 1)], radius=0.5)
            res = ampath.check(bad)
            self.assertFalse(res["ok"])
            self.assertFalse(res["gouge"]["ok"])
            self.assertEqual(res["gouge"]["violation"]["later_path"], 1)

    def test_stages_in_threads_give_the_same_paths(self):
        with ampath.Trivariate.model("helix") as v, ampath.cover(v, eps=3) as ps:
            results = [None] * 3

            def run(i):
                with ampath.order(ps) as o, ampath.mdr(o) as m:
                    results[i] = m.to_amp()
            threads = [threading.Thread(target=run, args=(i,)) for i in range(3)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        self.assertTrue(results[0])
        self.assertEqual(results.count(results[0]), 3)

    def test_field_and_slices_match_the_tool(self):
        tool("model", "helix", "-o", self.p("h.stl"))
        tool("field", self.p("h.stl"), "--field", "helix-square", "--spacing", 2, "--samples", 0,
             "-o", self.p("f.amp"))
        with ampath.Mesh.load(self.p("h.stl")) as m:
            with ampath.field(m, "helix-square", spacing=2) as ps:
                self.assertEqual(strip_comments(ps.to_amp()), strip_comments(read(self.p("f.amp"))))
                self.assertEqual(ps.stats["pieces"], len(ps))
            with ampath.Slices(m, 1.0) as sl:
                layers = sl.layers
                self.assertEqual(len(sl), len(layers))
                self.assertGreater(len(layers), 30)
                self.assertAlmostEqual(layers[0]["z_cut"], 0.5)
                self.assertTrue(all(r["points"] for L in layers for r in L["rings"]))
                self.assertGreater(sum(L["area"] for L in layers), 0)
            self.assertRaises(ampath.Error, len, sl)

    def test_close_from_another_thread_waits_for_the_call_reading_the_object(self):
        started, release, closing = threading.Event(), threading.Event(), threading.Event()
        result = {}

        def hold(_fraction):  # keeps the library call open until the main thread says so
            started.set()
            release.wait()

        with ampath.Trivariate.model("helix") as v:
            ps = ampath.cover(v, eps=3)
        worker = threading.Thread(target=lambda: result.setdefault("out", ampath.order(ps, progress=hold)))
        worker.start()
        self.assertTrue(started.wait(600))

        def close():
            closing.set()
            ps.close()
        closer = threading.Thread(target=close)
        closer.start()
        self.assertTrue(closing.wait(600))
        closer.join(0.5)
        self.assertTrue(closer.is_alive(), "close() freed the paths while order() was reading them")
        release.set()
        worker.join()
        closer.join()
        with result["out"] as out:
            self.assertGreater(len(out), 0)
        self.assertRaises(ampath.Error, len, ps)

    def test_printer_profiles(self):
        self.assertIn("generic", ampath.printer_names())
        p = ampath.Printer("voron-350")
        self.assertEqual(p.name, "voron-350")
        self.assertEqual(p.bed_max_x, 350)
        self.assertAlmostEqual(p.bead_width(), 1.125 * p.nozzle_diameter)
        with ampath.PathSet().add(square(), h=0.2) as ps:
            job = ampath.gcode(ps, printer=p)
        self.assertIn("voron-350", job.text)
        self.assertIn("M83", job.text)  # Klipper: relative E
        self.assertGreater(job.stats["time"], 0)


if __name__ == "__main__":
    unittest.main()
