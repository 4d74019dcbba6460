"""ampath.field's sweep field (`ampath field --field sweep --along SPINE.amp --side W`, paper Fig. 6) and its
regions (`--within R.stl`, `--without R.stl`: several fields in one model), byte for byte against the tool;
the merged parts then checked as `ampath check --mesh` checks them."""

import json

from amptest import TmpCase, ampath, as_tool_prints, read, strip_comments, tool

LEG = "ampath-paths 1\npath object 4\n14 2 13 1\n16 6 9 1\n19 15 6 1\n17 17 -1 1\n"  # docs/mesh.md
BOX = ((10, 4, -2), (25, 22, 7))  # around the crocodile's front leg (docs/mesh.md)


def box_stl(lo, hi):
    """An ASCII STL of the box [lo, hi], outward triangles."""
    def corner(c):
        return tuple(hi[k] if c[k] else lo[k] for k in range(3))
    quads = [((0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)), ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)),
             ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)), ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),
             ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)), ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1))]
    out = ["solid box"]
    for q in quads:
        for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            out.append("facet normal 0 0 0\nouter loop")
            out += ["vertex %g %g %g" % corner(c) for c in tri]
            out.append("endloop\nendfacet")
    return "\n".join(out + ["endsolid box"]) + "\n"


class SweepAndRegions(TmpCase):
    def setUp(self):
        super().setUp()
        tool("model", "crocodile-like", "-o", self.p("croc.stl"))
        with open(self.p("leg.amp"), "w") as f:
            f.write(LEG)
        with open(self.p("box.stl"), "w") as f:
            f.write(box_stl(*BOX))

    def field_tool(self, out, *args):
        r = tool("field", self.p("croc.stl"), "--samples", 0, "--json", "-o", self.p(out), *args)
        self.figures = json.loads(r.stdout)
        return strip_comments(read(self.p(out)))

    def assertSameFigures(self, stats, figures):
        """.stats against the tool's --json (amp_field_stats under the tool's names)."""
        names = {"curves": "curves", "pieces": "paths", "length_before": "length_before_mm",
                 "length_after": "length_after_mm", "radius": "radius_mm", "target": "covering_radius_mm",
                 "bound": "bound_mm", "inserted": "inserted_curves", "shell_paths": "shell_paths",
                 "shell_length": "shell_length_mm"}
        self.assertEqual(as_tool_prints({names[k]: stats[k] for k in names}),
                         {v: figures[v] for v in names.values()})
        self.assertEqual([stats["grid_a"], stats["grid_b"]], figures["grid"])
        self.assertEqual(bool(stats["bound_met"]), figures["bound_met"])

    def test_sweep_field_matches_the_tool_byte_for_byte(self):
        theirs = self.field_tool("leg.amp.out", "--field", "sweep", "--along", self.p("leg.amp"), "--side", 7,
                                 "--spacing", 2)
        figures = self.figures
        other = self.field_tool("leg5.amp.out", "--field", "sweep", "--along", self.p("leg.amp"), "--side", 5,
                                "--spacing", 2)
        self.assertNotEqual(theirs, other)  # the side matters: the comparison can fail
        spine = [(14, 2, 13), (16, 6, 9), (19, 15, 6), (17, 17, -1)]
        seen = []
        with ampath.Mesh.load(self.p("croc.stl")) as m, ampath.PathSet.read(self.p("leg.amp")) as leg:
            for along in (self.p("leg.amp"), leg, spine):  # a file, a PathSet (first path), points
                with ampath.field(m, "sweep", along=along, side=7, spacing=2, progress=seen.append) as ps:
                    self.assertSameBytes(strip_comments(ps.to_amp()), theirs, "sweep along %r" % (along,))
                    self.assertEqual(ps.stats["pieces"], len(ps))
                    self.assertSameFigures(ps.stats, figures)
            with ampath.field(m, "sweep", along=spine, side=5, spacing=2) as ps:
                self.assertSameBytes(strip_comments(ps.to_amp()), other, "sweep, side 5")
            # the library's refusals, with its message: one spine point; a spine turning back on itself
            for bad, name in (([(0, 0, 0)], "AMP_ERR_ARG"), ([(0, 0, 0), (10, 0, 0), (0, 0, 0.01)],
                                                            "AMP_ERR_GEOMETRY")):
                with self.assertRaises(ampath.Error) as cm:
                    ampath.field(m, "sweep", along=bad, side=7)
                self.assertEqual(cm.exception.name, name)
                with open(self.p("bad.amp"), "w") as f:
                    f.write("ampath-paths 1\npath object %d\n%s" % (len(bad), "".join(
                        "%g %g %g 1\n" % p for p in bad)))
                r = tool("field", self.p("croc.stl"), "--field", "sweep", "--along", self.p("bad.amp"), ok=False)
                self.assertEqual(r.returncode, 2)
                self.assertIn(cm.exception.message, r.stderr)
            with self.assertRaises(ampath.Error):
                ampath.field(m, "sweep", side=7)  # no spine
            with self.assertRaises(ampath.Error):
                ampath.field(m, "box", along=spine)  # a spine without the sweep
        self.assertGreater(len(seen), 2)
        self.assertLessEqual(seen[-1], 1.0)

    def test_within_and_without_match_the_tool_and_merge_into_one_checked_cover(self):
        leg = self.field_tool("part-leg.amp", "--field", "sweep", "--along", self.p("leg.amp"), "--side", 7,
                              "--spacing", 2, "--within", self.p("box.stl"))
        body = self.field_tool("part-body.amp", "--field", "box", "--spacing", 3, "--without", self.p("box.stl"))
        body_figures = self.figures
        whole = self.field_tool("whole-leg.amp", "--field", "sweep", "--along", self.p("leg.amp"), "--side", 7,
                                "--spacing", 2)
        self.assertNotEqual(leg, whole)  # the region cuts the field: the comparison can fail
        with ampath.Mesh.load(self.p("croc.stl")) as m, ampath.Mesh.load(self.p("box.stl")) as box:
            with ampath.field(m, "sweep", along=self.p("leg.amp"), side=7, spacing=2, within=self.p("box.stl")) as a:
                self.assertSameBytes(strip_comments(a.to_amp()), leg, "sweep --within")
                with ampath.field(m, "box", spacing=3, without=box) as b, ampath.field(m, "box", spacing=3,
                                                                                     without=[box]) as b2:
                    self.assertSameBytes(strip_comments(b.to_amp()), body, "box --without")
                    self.assertSameFigures(b.stats, body_figures)
                    self.assertEqual(b.to_amp(), b2.to_amp())  # one region or a list of them
                    # no vertex of the leg's part outside the box, none of the body's inside it (the seam
                    # is found to 1e-6 mm)
                    def inside(p, d):
                        return all(BOX[0][k] - d <= p[k] <= BOX[1][k] + d for k in range(3))
                    self.assertTrue(all(inside(p, 1e-3) for path in a for p in path.points))
                    self.assertFalse(any(inside(p, -1e-3) for path in b for p in path.points))
                    with ampath.PathSet().extend(a).extend(b) as merged:
                        merged.write(self.p("merged.amp"))
        r = tool("check", self.p("merged.amp"), "--mesh", self.p("croc.stl"), "--samples", 2000, "--json", ok=False)
        ours = ampath.check(self.p("merged.amp"), mesh=self.p("croc.stl"), samples=2000)
        ours["gouge"].pop("message", None)  # the tool's stderr line (the parts are not in print order)
        self.assertEqual(as_tool_prints(ours), as_tool_prints(json.loads(r.stdout)))
        self.assertEqual(ours["coverage"]["model"], "mesh")


if __name__ == "__main__":
    import unittest
    unittest.main()
