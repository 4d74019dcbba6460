"""The demo helix pipeline and a continuous slice through Python, compared byte for byte with the
`ampath` tool of the same tree (tools/demo.sh's options). Nothing here is stored: both sides run now."""

import shlex
import subprocess
import unittest

from amptest import TOOL, TmpCase, ampath, read, strip_comments, tool


def tool_chain(commands):
    """Start `ampath` commands one after the other in the background (sh -e)."""
    script = " && ".join(" ".join(shlex.quote(str(a)) for a in (TOOL,) + c) for c in commands)
    return subprocess.Popen(["sh", "-ec", script], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def finish(proc):
    _, err = proc.communicate(timeout=900)
    if proc.returncode != 0:
        raise AssertionError("ampath failed (%d): %s" % (proc.returncode, err))


class HelixPipeline(TmpCase):
    def test_demo_helix_pipeline_matches_the_tool_byte_for_byte(self):
        # the tool, as tools/demo.sh runs it, in the background while Python does the same (wall time)
        chain = tool_chain([("model", "helix", "-o", self.p("helix.spl")),
                            ("model", "helix", "-o", self.p("helix.stl")),
                            ("cover", self.p("helix.spl"), "--eps", 1, "--dir", "u", "-o", self.p("cover.amp")),
                            ("order", self.p("cover.amp"), "-o", self.p("ordered.amp")),
                            ("mdr", self.p("ordered.amp"), "--nominal", 0.5, "--trivariate", self.p("helix.spl"),
                             "-o", self.p("mdr.amp")),
                            ("support", self.p("mdr.amp"), "--mesh", self.p("helix.stl"), "-o", self.p("helix.amp")),
                            ("gcode", self.p("helix.amp"), "--printer", "generic", "-o", self.p("helix.gcode"))])
        outputs = {}

        # the same through Python; between stages the paths pass through their .amp text, as in the tool
        with ampath.Trivariate.model("helix") as v, ampath.Mesh.model("helix") as mesh:
            outputs["helix.spl"] = v.to_spl().encode()
            outputs["helix.stl"] = mesh.to_stl()
            stages = [("cover.amp", lambda _: ampath.cover(v, eps=1, dir="u")),
                      ("ordered.amp", lambda ps: ampath.order(ps)),
                      ("mdr.amp", lambda ps: ampath.mdr(ps, nominal=0.5)),
                      ("helix.amp", lambda ps: ampath.support(ps, mesh))]
            ps = None
            for name, stage in stages:
                out = stage(ps)
                outputs[name] = strip_comments(out.to_amp())
                if ps is not None:
                    ps.close()
                ps = out.as_written()
                out.close()
            job = ampath.gcode(ps, printer="generic")
            outputs["helix.gcode"] = job.text.encode()
            finish(chain)
            stats = ampath.gcode(ps, self.p("py.gcode"), printer="generic").stats
            ps.close()
        for name, data in outputs.items():
            theirs = read(self.p(name))
            self.assertSameBytes(data, strip_comments(theirs) if name.endswith(".amp") else theirs, name)
        self.assertSameBytes(read(self.p("py.gcode")), read(self.p("helix.gcode")), "helix.gcode (file)")
        self.assertEqual(stats["lines"], job.text.count("\n"))


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
