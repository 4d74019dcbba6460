"""ampath.check against `ampath check ... --json` on the same inputs: every section (coverage of a trivariate
and of a mesh, gouge, strokes with and without layer polygons, support holding) with the same keys and
the same figures (the tool prints numbers with 12 significant digits; only the timings differ)."""

import json
import struct

from amptest import TmpCase, ampath, as_tool_prints, tool


class CheckFigures(TmpCase):
    def setUp(self):
        super().setUp()
        # the helix: covered, ordered and supported by the tool (planar support paths run the stroke check;
        # whether every object path is held is up to `ampath support`: the figures must agree either way)
        tool("model", "helix", "-o", self.p("h.stl"))
        tool("cover", "helix", "--eps", 3, "--dir", "u", "-o", self.p("c.amp"))
        tool("order", self.p("c.amp"), "-o", self.p("o.amp"))
        tool("support", self.p("o.amp"), "--mesh", self.p("h.stl"), "-o", self.p("s.amp"))

    def same(self, amp, tool_args, **kw):
        """The tool's figures and Python's on @amp; returns them (after asserting they are equal)."""
        r = tool("check", amp, "--json", *tool_args, ok=False)
        self.assertIn(r.returncode, (0, 1), r.stderr)
        theirs = json.loads(r.stdout)
        ours = ampath.check(amp, **kw)
        ours["gouge"].pop("message", None)  # the tool prints it on stderr, without --json (below)
        self.assertEqual(as_tool_prints(ours), as_tool_prints(theirs), " ".join(map(str, tool_args)))
        self.assertEqual(ours["ok"], r.returncode == 0)
        return ours, theirs

    def test_mesh_coverage_and_support_equal_the_tool(self):
        ours, _ = self.same(self.p("s.amp"), ["--mesh", self.p("h.stl"), "--samples", 2000],
                            mesh=self.p("h.stl"), samples=2000)
        cov, sup = ours["coverage"], ours["support"]
        self.assertEqual((cov["ran"], cov["model"]), (True, "mesh"))
        self.assertEqual(cov["ok"], cov["coverage_gap_mm"] <= cov["eps"] and cov["vertices_outside"] == 0)
        self.assertGreater(cov["samples"], 0)
        self.assertTrue(sup["ran"])  # the file has support paths
        self.assertEqual(sup["ok"], sup["failures"] == 0)
        self.assertEqual(min(sup["unheld_paths"], 100), len(sup["unheld_path_list"]))  # the first 100
        # with its pads `ampath support` leaves none of this helix's object paths unheld (65 with --no-pads)
        self.assertEqual(sup["failures"], 0)
        self.assertTrue(ours["strokes"]["ran"] and ours["gouge"]["ok"])
        # options of the tool, as keyword arguments: a wider tolerance outside, a longer bridge, a Mesh object
        with ampath.Mesh.load(self.p("h.stl")) as m:
            ours, _ = self.same(self.p("s.amp"), ["--mesh", self.p("h.stl"), "--samples", 500, "--seed", 7,
                                                  "--eps", 2, "--tol", 0.1, "--bridge", 30, "--overhang", 60,
                                                  "--max-gap", 2],
                                mesh=m, samples=500, seed=7, eps=2, tol=0.1, bridge=30, overhang_deg=60, max_gap=2)
        self.assertEqual(ours["coverage"]["eps"], 2)
        self.assertEqual(ours["support"]["bridge_mm"], 30)

    def test_trivariate_coverage_takes_the_eps_cover_recorded(self):
        ours, _ = self.same(self.p("s.amp"), ["--trivariate", "helix", "--samples", 2000],
                            trivariate="helix", samples=2000)
        self.assertEqual((ours["coverage"]["eps"], ours["coverage"]["eps_from"]), (3, "path file"))
        self.assertTrue(ours["coverage"]["ok"])
        with ampath.Trivariate.model("helix") as v, ampath.PathSet.read(self.p("o.amp")) as ps:
            ours, _ = self.same(self.p("o.amp"), ["--trivariate", "helix", "--samples", 1000, "--no-gouge",
                                                  "--support", "--eps", 0.4],
                                trivariate=v, samples=1000, skip=("gouge",), support=True, eps=0.4)
            self.assertFalse(ours["coverage"]["ok"])  # a gap above 0.4 mm
            self.assertEqual(ours["gouge"], {"ran": False, "reason": "skipped on request"})
            self.assertEqual(ampath.check(ps, skip="gouge")["gouge"]["reason"], "skipped on request")
            self.assertTrue(ours["support"]["ran"])  # no support paths, but asked for
            self.assertEqual(ampath.check(ps, trivariate=v, samples=1000)["coverage"]["eps_from"], "path file")
        with ampath.PathSet.read(self.p("o.amp")) as ps, ampath.PathSet().extend(ps) as copy:
            self.assertEqual(ampath.check(copy, trivariate="helix", samples=500)["coverage"]["eps_from"],
                             "largest radius")  # made in memory: no file to read the eps from

    def test_strokes_against_the_layer_polygons_equal_the_tool(self):
        tool("slice", self.p("h.stl"), "--layer", 0.6, "--continuous", "-o", self.p("cont.amp"))
        ours, _ = self.same(self.p("cont.amp"), ["--mesh", self.p("h.stl"), "--layer", 0.6],
                            mesh=self.p("h.stl"), layer=0.6)
        st = ours["strokes"]
        self.assertTrue(st["ran"] and st["ok"])
        self.assertEqual(ours["coverage"]["reason"], "--layer given: the mesh is used for the stroke check")
        # checked against another layer height, the strokes match no layer: the check fails, as the tool's
        ours, _ = self.same(self.p("cont.amp"), ["--mesh", self.p("h.stl"), "--layer", 0.5],
                            mesh=self.p("h.stl"), layer=0.5)
        self.assertFalse(ours["strokes"]["ok"])
        self.assertGreater(ours["strokes"]["paths_without_layer"], 0)

    def test_slivers_and_support_of_a_sliced_job_count_as_in_the_tool(self):
        # a 20 x 20 x 2 mm block with a wall 4 um thin and 3 mm tall on it: its layers above the block are
        # slivers no bead could follow, printed by nothing and asked for by neither check
        def box(lo, hi):
            c = [(hi[0] if i in (1, 2, 5, 6) else lo[0], hi[1] if i in (2, 3, 6, 7) else lo[1],
                  hi[2] if i >= 4 else lo[2]) for i in range(8)]
            f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5), (2, 3, 7),
                 (2, 7, 6), (3, 0, 4), (3, 4, 7)]
            return [(c[a], c[b], c[d]) for a, b, d in f]
        tris = box((0, 0, 0), (20, 20, 2)) + box((5, 10, 1.5), (15, 10.004, 5))
        with open(self.p("w.stl"), "wb") as out:
            out.write(b"\0" * 80 + struct.pack("<I", len(tris)))
            for t in tris:
                out.write(struct.pack("<12fH", 0, 0, 0, *t[0], *t[1], *t[2], 0))
        tool("slice", self.p("w.stl"), "--layer", 0.2, "--continuous", "-o", self.p("w.amp"))
        ours, _ = self.same(self.p("w.amp"), ["--mesh", self.p("w.stl"), "--layer", 0.2],
                            mesh=self.p("w.stl"), layer=0.2)
        self.assertTrue(ours["strokes"]["ok"])
        self.assertEqual(ours["strokes"]["layers_without_paths"], 0)
        # the helix sliced, with support on its layers: the support paths lie outside the section by design
        tool("slice", self.p("h.stl"), "--layer", 0.6, "--continuous", "-o", self.p("hs.amp"))
        tool("support", self.p("hs.amp"), "--mesh", self.p("h.stl"), "-o", self.p("hss.amp"))
        ours, _ = self.same(self.p("hss.amp"), ["--mesh", self.p("h.stl"), "--layer", 0.6, "--support"],
                            mesh=self.p("h.stl"), layer=0.6, support=True)
        self.assertTrue(ours["strokes"]["ok"] and ours["support"]["ok"])
        self.assertEqual(ours["strokes"]["outside"], 0)

    def test_a_gouge_and_a_bead_in_the_air_fail_as_in_the_tool(self):
        with ampath.PathSet() as bad:
            bad.add([(0, 0, 5), (10, 0, 5)], radius=0.5)  # printed first, high: then the head hits it
            bad.add([(0, 0, 1), (10, 0, 1)], radius=0.5)
            bad.write(self.p("bad.amp"))
        ours, _ = self.same(self.p("bad.amp"), ["--support"], support=True)
        self.assertFalse(ours["gouge"]["ok"])
        message = ampath.check(self.p("bad.amp"))["gouge"]["message"]
        self.assertIn("ampath check: %s\n" % message, tool("check", self.p("bad.amp"), ok=False).stderr)
        self.assertEqual(ours["gouge"]["violation"]["later_path"], 1)
        self.assertFalse(ours["support"]["ok"])  # the path at z = 5 is printed over nothing
        self.assertEqual(ours["support"]["unheld_path_list"][0], 0)
        ours, _ = self.same(self.p("bad.amp"), [])
        self.assertEqual(ours["support"]["reason"],
                         "no support paths (--support requires every object path to be held)")

    def test_bad_options_raise_as_the_tool_refuses_them(self):
        for kw in (dict(trivariate="helix", mesh=self.p("h.stl")), dict(eps=0), dict(samples=0),
                   dict(layer=0.3), dict(tol=-1), dict(overhang_deg=90), dict(bridge=-1), dict(skip=("speed",))):
            with self.assertRaises(ampath.Error, msg=str(kw)) as cm:
                ampath.check(self.p("o.amp"), **kw)
            self.assertEqual(cm.exception.name, "AMP_ERR_ARG")
        with self.assertRaises(ampath.Error) as cm:
            ampath.check(self.p("o.amp"), trivariate=self.p("missing.spl"))
        self.assertIn("missing.spl", cm.exception.message)


if __name__ == "__main__":
    import unittest
    unittest.main()
