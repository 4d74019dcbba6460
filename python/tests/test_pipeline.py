"""The demo helix pipeline and a continuous slice through Python, compared byte for byte with the
`ampath` tool of the same tree (tools/demo.sh's options). Nothing here is stored: both sides run now."""

import json
import shlex
import subprocess
import unittest
import warnings

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


class History(TmpCase):
    def test_written_paths_keep_the_tools_history_lines(self):
        # the `# ampath ...` lines of each stage, as the tool writes them: the file is the tool's byte for byte,
        # and `ampath check` (and ampath.check) find the eps cover noted (without them: the largest radius)
        for args in (("cover", "helix", "--eps", 2, "--dir", "u", "-o", self.p("c.amp")),
                     ("order", self.p("c.amp"), "-o", self.p("o.amp")),
                     ("mdr", self.p("o.amp"), "--nominal", 0.5, "-o", self.p("m.amp")),
                     ("model", "helix", "-o", self.p("h.stl")),
                     ("support", self.p("m.amp"), "--mesh", self.p("h.stl"), "-o", self.p("s.amp"))):
            tool(*args)
        with ampath.Trivariate.model("helix") as v, ampath.Mesh.model("helix") as mesh:
            ps = ampath.cover(v, eps=2, dir="u").as_written()
            ps = ampath.order(ps).as_written()
            ps = ampath.mdr(ps, nominal=0.5).as_written()
            ps = ampath.support(ps, mesh).as_written()
            ps.write(self.p("py.amp"))
            report = ampath.check(ps, trivariate=v)
        self.assertSameBytes(read(self.p("py.amp")), read(self.p("s.amp")), "support output with its history")
        self.assertEqual((report["coverage"]["eps"], report["coverage"]["eps_from"]), (2.0, "path file"))
        tool("check", self.p("py.amp"), "--trivariate", "helix", "--no-gouge", "--no-support")


class SupportPads(TmpCase):
    def test_pads_are_on_by_default_and_off_with_pads_false_as_in_the_tool(self):
        tool("cover", "helix", "--eps", 3, "--dir", "u", "-o", self.p("c.amp"))
        tool("order", self.p("c.amp"), "-o", self.p("o.amp"))
        tool("model", "helix", "-o", self.p("h.stl"))
        tool("support", self.p("o.amp"), "--mesh", self.p("h.stl"), "-o", self.p("pads.amp"))
        tool("support", self.p("o.amp"), "--mesh", self.p("h.stl"), "--no-pads", "-o", self.p("rows.amp"))
        with ampath.PathSet.read(self.p("o.amp")) as ps, ampath.Mesh.load(self.p("h.stl")) as mesh:
            with ampath.support(ps, mesh) as padded, ampath.support(ps, mesh, pads=False) as rows:
                self.assertGreater(padded.stats["pads"], 0)
                self.assertEqual(rows.stats["pads"], 0)
                self.assertSameBytes(strip_comments(padded.to_amp()), strip_comments(read(self.p("pads.amp"))),
                                     "support with pads")
                self.assertSameBytes(strip_comments(rows.to_amp()), strip_comments(read(self.p("rows.amp"))),
                                     "support without pads")


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

    def test_the_overlap_cap_is_an_option_as_in_the_tool(self):
        tool("model", "helix", "-o", self.p("helix.stl"))
        tool("slice", self.p("helix.stl"), "--layer", 0.3, "--continuous", "--no-overlap-cap", "-o", self.p("raw.amp"))
        with ampath.Mesh.load(self.p("helix.stl")) as mesh:
            with ampath.slice(mesh, 0.3, continuous=True) as capped, \
                    ampath.slice(mesh, 0.3, continuous=True, overlap_cap=0) as raw:
                self.assertSameBytes(strip_comments(raw.to_amp()), strip_comments(read(self.p("raw.amp"))),
                                     "continuous slice without the cap")
                self.assertGreater(capped.stats["narrowed_islands"], 0)
                self.assertEqual(raw.stats["narrowed_islands"], 0)
                self.assertLess(capped.volume(), raw.volume())


    def test_a_failing_final_check_slices_again_with_the_per_island_verifier(self):
        # as the tool: the layers are made without the per-island verifier and checked once; only when that
        # check fails are they made again with it (and checked again, raising if they still fail)
        import ampath.pipeline as pl
        tool("model", "helix", "-o", self.p("helix.stl"))
        tool("slice", self.p("helix.stl"), "--layer", 0.3, "--continuous", "-o", self.p("cont.amp"))
        calls, real = [], pl.Slices._check_strokes

        def failing_once(sl, ps, raise_on_failure=True):
            tot = real(sl, ps, raise_on_failure)
            calls.append(raise_on_failure)
            return dict(tot, failed_paths=1) if len(calls) == 1 else tot
        pl.Slices._check_strokes = failing_once
        try:
            with ampath.Mesh.load(self.p("helix.stl")) as mesh, ampath.slice(mesh, 0.3, continuous=True) as cont:
                amp = strip_comments(cont.to_amp())
                self.assertEqual(cont.stats["failed_paths"], 0)
        finally:
            pl.Slices._check_strokes = real
        self.assertEqual(calls, [False, True])
        # made twice, appended once: the same paths as the tool's
        self.assertSameBytes(amp, strip_comments(read(self.p("cont.amp"))), "continuous slice after the retry")


# a profile whose start and end G-code read the placed job (PrusaSlicer's macro language)
MACRO_INI = ("bed_shape = 0x0,250x0,250x210,0x210\nmax_print_height = 210\nprinter_model = MK3S\n"
             "print_settings_id = 0.15mm QUALITY @MK3\n"
             "start_gcode = M862.3 P \"[printer_model]\"\\nM555 X{first_layer_print_min[0]} Y{first_layer_print_min[1]}"
             " W{first_layer_print_size[0]} H{first_layer_print_size[1]}\\n"
             "{if print_settings_id=~/.*(DETAIL|QUALITY) @MK3.*/}M907 E430{endif}\\nM109 S[first_layer_temperature]\n"
             "end_gcode = {if max_layer_z < max_print_height}G1 Z{min(max_layer_z+1, max_print_height)} F720{endif}"
             "\\nM117 {total_layer_count} layers\\nM84\n")


class PrinterMacros(TmpCase):
    def test_start_and_end_macros_see_the_placed_job_as_in_the_tool(self):
        with open(self.p("m.ini"), "w") as f:
            f.write(MACRO_INI)
        with ampath.PathSet() as ps:
            for z, a in ((0.2, 5), (0.4, 3)):  # two layers: a 10 mm square, a 6 mm one
                ps.add([(-a, -a, z), (a, -a, z), (a, a, z), (-a, a, z), (-a, -a, z)], radius=0.225, h=0.2)
            ps.write(self.p("m.amp"))
        tool("gcode", self.p("m.amp"), "--printer", self.p("m.ini"), "--place", "60,70", "--hotend", 230,
             "-o", self.p("m.gcode"))
        with ampath.PathSet.read(self.p("m.amp")) as ps:
            job = ampath.gcode(ps, printer=self.p("m.ini"), place=(60, 70), hotend_temp=230,
                               first_layer_hotend_temp=230)
        self.assertSameBytes(job.text.encode(), read(self.p("m.gcode")), "G-code with macros")
        for line in ("M862.3 P \"MK3S\"", "M555 X55 Y65 W10 H10", "M907 E430", "M109 S230", "G1 Z1.4 F720",
                     "M117 2 layers"):
            self.assertIn("\n%s\n" % line, job.text)
        self.assertEqual(ampath.Printer(self.p("m.ini")).variables()["print_settings_id"], "0.15mm QUALITY @MK3")


# (tool options, the same as Python keyword arguments): every option of `slice --continuous`
OPTION_SETS = [
    (("--printer", "{ini}", "--infill", 30, "--tour", "merge", "--bottom", 0, "--top", 1.2, "--no-corners",
      "--pseudo", "--eps-c", 0.5, "--grid", "tri"),
     dict(printer="{ini}", infill=30, tour="merge", skin_bottom=0, skin_top=1.2, support_corners=0, pseudo_edges=1,
          eps_c=0.5, grid="tri")),
    (("--printer", "{ini}", "--radius", 0.3, "--cell", 3, "--offset", 0.25, "--support-stretches", "--grid", "hex"),
     dict(printer="{ini}", radius=0.3, cell=3, offset=0.25, support_stretches=1, grid="hex")),
    (("--nozzle", 0.6, "--no-join"), dict(nozzle=0.6, join=False)),
    (("--no-perimeter",), dict(perimeters=0)),
]
# --json figures and the Python .stats key they are
JSON_KEYS = {"islands": "islands", "island_strokes": "island_strokes", "regions": "regions",
             "skin_regions": "skin_regions", "support_corners": "support_corners", "extrusion_starts":
             "extrusion_starts", "crossings": "crossings", "repeated_edges": "repeated_edges", "outside": "outside",
             "failed_paths": "failed_paths", "overhang_pairs": "overhang_pairs", "eps_c": "eps_c"}


class ContinuousOptions(TmpCase):
    def test_every_option_does_what_the_tool_does(self):
        """Each option set through the tool and through Python: the same bytes and figures when the tool's
        check of every path passes, the same Error (AMP_ERR_CHECK, the tool's first message) when it exits 1."""
        tool("model", "helix", "-o", self.p("helix.stl"))
        ini = self.p("p06.ini")
        with open(ini, "w") as f:
            f.write("# a PrusaSlicer printer with a 0.6 mm nozzle\nnozzle_diameter = 0.6,0.6\n"
                    "bed_shape = 0x0,250x0,250x210,0x210\n")
        outputs = []
        with ampath.Mesh.load(self.p("helix.stl")) as mesh, ampath.Slices(mesh, 0.3) as sl:
            for k, (args, kw) in enumerate(OPTION_SETS):
                args = [ini if a == "{ini}" else a for a in args]
                kw = {n: ini if v == "{ini}" else v for n, v in kw.items()}
                amp = self.p("o%d.amp" % k)
                r = tool("slice", self.p("helix.stl"), "--layer", 0.3, "--continuous", "--json", "-o", amp, *args,
                         ok=False)
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    if r.returncode != 0:
                        first = [l for l in r.stderr.splitlines() if "fails its check" in l][0]
                        with self.assertRaises(ampath.Error) as cm:
                            sl.continuous(**kw)
                        self.assertEqual(cm.exception.name, "AMP_ERR_CHECK")
                        self.assertIn(first[len("ampath slice: "):], cm.exception.message)
                        continue
                    with sl.continuous(**kw) as ps:
                        data = strip_comments(ps.to_amp())
                        stats = ps.stats
                self.assertSameBytes(data, strip_comments(read(amp)),
                                     "slice --continuous %s" % " ".join(map(str, args)))
                figures = json.loads(r.stdout)
                for j, py in JSON_KEYS.items():
                    self.assertEqual(stats[py], figures[j], "%s with %s" % (j, args))
                self.assertEqual(len(stats["overhang_mm"]), len(figures["overhang_mm"]))
                for a, b in zip(stats["overhang_mm"], figures["overhang_mm"]):
                    self.assertAlmostEqual(a, b, 8)
                # the tool's stderr warning about overhangs is a RuntimeWarning
                self.assertEqual(any("eps-continuous" in str(w.message) for w in caught),
                                 figures["overhang_pairs"] > 0)
                outputs.append(data)
        self.assertGreaterEqual(len(outputs), 2)
        self.assertEqual(len(set(outputs)), len(outputs))  # the option sets make different paths

    def test_the_printer_sets_the_bead_of_strokes_and_polygons(self):
        tool("model", "helix", "-o", self.p("helix.stl"))
        ini = self.p("p06.ini")
        with open(ini, "w") as f:
            f.write("nozzle_diameter = 0.6\n")
        tool("slice", self.p("helix.stl"), "--layer", 0.3, "--polygons", "--printer", ini, "-o", self.p("poly.amp"))
        with ampath.Mesh.load(self.p("helix.stl")) as mesh:
            with ampath.slice(mesh, 0.3, printer=ini) as poly:
                self.assertSameBytes(strip_comments(poly.to_amp()), strip_comments(read(self.p("poly.amp"))),
                                     "polygons with --printer")
                self.assertAlmostEqual(poly[0].points[0][3], 0.3375)  # 1.125 x 0.6 mm wide
            with ampath.slice(mesh, 0.3, continuous=True, nozzle=0.8, radius=0.25) as ps:
                # the radius wins, as --radius (the first layer's sliver is narrowed to its slab: the widest bead)
                self.assertEqual(max(v[3] for path in ps for v in path.points), 0.25)
            for bad in (dict(infill=30, cell=3), dict(infill=150), dict(tour="euler"), dict(grid="strips"),
                        dict(skin_top=-1), dict(eps_c=2), dict(nozzle=0), dict(cell=0)):
                with self.assertRaises(ampath.Error, msg=str(bad)) as cm:
                    ampath.slice(mesh, 0.3, continuous=True, **bad).close()
                self.assertEqual(cm.exception.name, "AMP_ERR_ARG")
            with self.assertRaises(TypeError):
                ampath.slice(mesh, 0.3, continuous=True, no_such_option=1)


if __name__ == "__main__":
    unittest.main()
