"""The demo helix pipeline and a continuous slice through Python, compared byte for byte with the
`ampath` tool of the same tree (tools/demo.sh's options). Nothing here is stored: both sides run now."""

import unittest

from amptest import TmpCase, ampath, read, strip_comments, tool


class HelixPipeline(TmpCase):
    def test_demo_helix_pipeline_matches_the_tool_byte_for_byte(self):
        # the tool, as tools/demo.sh runs it
        tool("model", "helix", "-o", self.p("helix.spl"))
        tool("model", "helix", "-o", self.p("helix.stl"))
        tool("cover", self.p("helix.spl"), "--eps", 1, "--dir", "u", "-o", self.p("cover.amp"))
        tool("order", self.p("cover.amp"), "-o", self.p("ordered.amp"))
        tool("mdr", self.p("ordered.amp"), "--nominal", 0.5, "-o", self.p("mdr.amp"))
        tool("support", self.p("mdr.amp"), "--mesh", self.p("helix.stl"), "-o", self.p("helix.amp"))
        tool("gcode", self.p("helix.amp"), "--printer", "generic", "-o", self.p("helix.gcode"))

        # the same through Python; between stages the paths pass through their .amp text, as in the tool
        with ampath.Trivariate.model("helix") as v, ampath.Mesh.model("helix") as mesh:
            self.assertSameBytes(v.to_spl().encode(), read(self.p("helix.spl")), "helix.spl")
            self.assertSameBytes(mesh.to_stl(), read(self.p("helix.stl")), "helix.stl")
            stages = [("cover.amp", lambda _: ampath.cover(v, eps=1, dir="u")),
                      ("ordered.amp", lambda ps: ampath.order(ps)),
                      ("mdr.amp", lambda ps: ampath.mdr(ps, nominal=0.5)),
                      ("helix.amp", lambda ps: ampath.support(ps, mesh))]
            ps = None
            for name, stage in stages:
                out = stage(ps)
                self.assertSameBytes(strip_comments(out.to_amp()), strip_comments(read(self.p(name))), name)
                if ps is not None:
                    ps.close()
                ps = out.as_written()
                out.close()
            job = ampath.gcode(ps, printer="generic")
            self.assertSameBytes(job.text.encode(), read(self.p("helix.gcode")), "helix.gcode (string)")
            stats = ampath.gcode(ps, self.p("py.gcode"), printer="generic").stats
            self.assertSameBytes(read(self.p("py.gcode")), read(self.p("helix.gcode")), "helix.gcode (file)")
            self.assertEqual(stats["lines"], job.text.count("\n"))
            ps.close()


class ContinuousSlice(TmpCase):
    def test_continuous_slice_and_its_gcode_match_the_tool(self):
        tool("model", "helix", "-o", self.p("helix.stl"))
        tool("slice", self.p("helix.stl"), "--layer", 0.3, "--continuous", "-o", self.p("cont.amp"))
        tool("slice", self.p("helix.stl"), "--layer", 0.3, "--polygons", "-o", self.p("poly.amp"))
        tool("gcode", self.p("cont.amp"), "--printer", "ender3", "--place", "100,110", "--arcs",
             "-o", self.p("cont.gcode"))
        with ampath.Mesh.load(self.p("helix.stl")) as mesh:
            with ampath.slice(mesh, 0.3, continuous=True) as cont, ampath.slice(mesh, 0.3) as poly:
                self.assertGreater(cont.stats["strokes"], 0)
                self.assertSameBytes(strip_comments(cont.to_amp()), strip_comments(read(self.p("cont.amp"))),
                                     "continuous slice")
                self.assertSameBytes(strip_comments(poly.to_amp()), strip_comments(read(self.p("poly.amp"))),
                                     "polygon slice")
                with cont.as_written() as ps:
                    job = ampath.gcode(ps, printer="ender3", place=(100, 110), arcs=1)
                    moved = ampath.gcode(ps, printer="ender3", place=(100, 111), arcs=1)
        # the comparison sees a one-millimetre change of one option
        self.assertNotEqual(moved.text.encode(), read(self.p("cont.gcode")))
        self.assertSameBytes(job.text.encode(), read(self.p("cont.gcode")), "continuous G-code")
        self.assertEqual(job.printer.name, "ender3")


if __name__ == "__main__":
    unittest.main()
