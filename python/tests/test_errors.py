"""Error paths raise ampath.Error with the status and the library's own message (the one the tool prints)."""

import unittest

from amptest import TmpCase, ampath, tool, tool_message


class Errors(TmpCase):
    def write(self, name, text):
        with open(self.p(name), "w") as f:
            f.write(text)
        return self.p(name)

    def test_missing_file_raises_io_error_with_the_tool_message(self):
        missing = self.p("missing.amp")
        with self.assertRaises(ampath.Error) as cm:
            ampath.PathSet.read(missing)
        e = cm.exception
        self.assertEqual((e.status, e.name), (-5, "AMP_ERR_IO"))
        self.assertIn(missing, e.message)
        self.assertEqual(e.message, tool_message("mdr", tool("mdr", missing, ok=False).stderr))

    def test_malformed_amp_raises_parse_error_with_line(self):
        bad = self.write("bad.amp", "ampath-paths 1\npath object 2\n0 0 0 0.5\n1 2 x 0.5\n")
        with self.assertRaises(ampath.Error) as cm:
            ampath.PathSet.read(bad)
        e = cm.exception
        self.assertEqual(e.name, "AMP_ERR_PARSE")
        self.assertEqual(e.line, 4)
        self.assertEqual(e.reason, "parse error")
        r = tool("order", bad, ok=False)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(e.message, tool_message("order", r.stderr))
        self.assertIn(e.message, str(e))

    def test_an_empty_trivariate_raises_instead_of_crashing(self):
        # Trivariate() (no control points) crashed the interpreter in eval and volume
        t = ampath.Trivariate()
        with self.assertRaises(ampath.Error) as cm:
            t.eval(0.5, 0.5, 0.5)
        self.assertEqual(cm.exception.name, "AMP_ERR_ARG")
        self.assertEqual(t.volume(), 0.0)

    def test_a_failed_spl_write_keeps_the_old_file(self):
        old = self.write("old.spl", "old")
        with self.assertRaises(ampath.Error):
            ampath.Trivariate().write(old)  # nothing to write: it emptied the file before
        with open(old) as f:
            self.assertEqual(f.read(), "old")

    def test_cover_refuses_a_runaway_covering_as_the_tool_does(self):
        with ampath.Trivariate.model("helix") as v:
            with self.assertRaises(ampath.Error) as cm:
                ampath.cover(v, eps=0.001)
            self.assertEqual(cm.exception.name, "AMP_ERR_LIMIT")
            self.assertIn("covering curves estimated", cm.exception.message)
            r = tool("cover", "helix", "--eps", "0.001", "-o", self.p("x.amp"), ok=False)
            self.assertEqual(r.returncode, 2)
            self.assertIn("2.26e+08 covering curves", r.stderr)
            self.assertIn("2.26e+08 covering curves", cm.exception.message)

    def test_support_takes_a_mesh_file_name_and_refuses_other_types(self):
        # check and field took a file name, support an AttributeError
        tool("model", "twisted-bridge", "-o", self.p("m.stl"))
        ps = ampath.PathSet()
        ps.add([(0, 0, 0.5), (10, 0, 0.5)], radius=0.5)
        with ampath.Mesh.load(self.p("m.stl")) as m:
            self.assertEqual(ampath.support(ps, self.p("m.stl")).to_amp(), ampath.support(ps, m).to_amp())
        with self.assertRaises(TypeError):
            ampath.support(ps, None)

    def test_bad_stl_and_spl_raise(self):
        stl = self.write("bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n")
        with self.assertRaises(ampath.Error) as cm:
            ampath.Mesh.load(stl)
        self.assertEqual(cm.exception.name, "AMP_ERR_PARSE")
        with self.assertRaises(ampath.Error) as cm:
            ampath.Trivariate.load(self.write("bad.spl", "ampath-spline 1\nkind cube\n"))
        self.assertEqual(cm.exception.name, "AMP_ERR_PARSE")

    def test_bad_head_option_raises_range_error_with_the_tool_message(self):
        good = self.write("ok.amp", "ampath-paths 1\npath object 2\n0 0 0 0.5\n10 0 0 0.5\n")
        with ampath.PathSet.read(good) as ps:
            with self.assertRaises(ampath.Error) as cm:
                ampath.order(ps, theta_deg=95)
        self.assertEqual(cm.exception.name, "AMP_ERR_RANGE")
        self.assertEqual(cm.exception.message, tool_message("order", tool("order", good, "--theta", 95,
                                                                          ok=False).stderr))

    def test_bad_values_refused_by_the_library_or_the_binding_raise_error(self):
        good = self.write("ok.amp", "ampath-paths 1\npath object 2\n0 0 0 0.5\n10 0 0 0.5\n")
        with ampath.PathSet.read(good) as ps:
            with self.assertRaises(ampath.Error) as cm:
                ampath.mdr(ps, nominal=-1)
            self.assertEqual(cm.exception.name, "AMP_ERR_RANGE")
            with self.assertRaises(ampath.Error) as cm:
                ps.add([(0, 0, 0)], role="scaffold")
            self.assertEqual(cm.exception.name, "AMP_ERR_ARG")
        with ampath.Trivariate.model("helix") as v, self.assertRaises(ampath.Error) as cm:
            ampath.cover(v, eps=1, dir="x")
        self.assertIn("dir must be u, v or w", cm.exception.message)

    def test_bad_printer_and_unknown_option(self):
        good = self.write("ok.amp", "ampath-paths 1\npath object 2\n0 0 0.2 0.5\n10 0 0.2 0.5\n")
        with ampath.PathSet.read(good) as ps:
            with self.assertRaises(ampath.Error) as cm:
                ampath.gcode(ps, printer="no-such-printer")
            self.assertEqual(cm.exception.message, tool_message(
                "gcode", tool("gcode", good, "--printer", "no-such-printer", ok=False).stderr))
            with self.assertRaises(TypeError):
                ampath.gcode(ps, no_such_option=1)
            with self.assertRaises(ampath.Error) as cm:  # an option out of range, refused by the writer
                ampath.gcode(ps, filament_diameter=-1)
            self.assertIn("filament", cm.exception.message)
            with self.assertRaises(ampath.Error) as cm:  # a job that does not fit the bed
                ampath.gcode(ps, place=(1000, 1000))
            self.assertEqual(cm.exception.message, tool_message(
                "gcode", tool("gcode", good, "--place", "1000,1000", ok=False).stderr))

    def test_nothing_is_written_when_the_job_is_refused(self):
        good = self.write("ok.amp", "ampath-paths 1\npath object 2\n0 0 0.2 0.5\n10 0 0.2 0.5\n")
        out = self.write("old.gcode", "old\n")
        with ampath.PathSet.read(good) as ps, self.assertRaises(ampath.Error):
            ampath.gcode(ps, out, place=(1000, 1000))
        with open(out) as f:
            self.assertEqual(f.read(), "old\n")


if __name__ == "__main__":
    unittest.main()
