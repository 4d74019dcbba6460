"""Pictures from Python are the tool's (`ampath preview`) byte for byte: both come from lib/preview.c."""

import unittest

from amptest import TmpCase, ampath, read, tool


class Preview(TmpCase):
    def test_png_and_svg_bytes_equal_the_tool_files(self):
        with ampath.Trivariate.model("helix") as v, ampath.cover(v, eps=3) as ps:
            ps.write(self.p("c.amp"))
            with ampath.PathSet.read(self.p("c.amp")) as back:
                for fmt, width in (("png", 1600), ("svg", 1600), ("png", 500)):
                    out = self.p("c-%d.%s" % (width, fmt))
                    tool("preview", self.p("c.amp"), "-o", out, "--width", width)
                    st = {}
                    data = ampath.preview(back, fmt, width=width, stats=st)
                    self.assertSameBytes(data, read(out), out)
                    self.assertEqual(st["bytes"], len(data))
                    self.assertEqual(st["height"], width // 2 + 110)
                    ampath.preview(back, output=self.p("py." + fmt), width=width)
                    self.assertSameBytes(read(self.p("py." + fmt)), read(out), "file " + out)
        self.assertTrue(data.startswith(b"\x89PNG\r\n\x1a\n"))

    def test_progress_of_the_read_and_the_drawing_rises_to_one_and_changes_no_byte(self):
        with ampath.Trivariate.model("helix") as v, ampath.cover(v, eps=3) as ps:
            ps.write(self.p("c.amp"))
        heard = {"read": [], "draw": []}
        with ampath.PathSet.read(self.p("c.amp"), progress=heard["read"].append) as back:
            plain = ampath.preview(back, "svg", width=800)
            drawn = ampath.preview(back, "svg", width=800, progress=heard["draw"].append)
            self.assertSameBytes(drawn, plain, "svg with a progress report")
            with self.assertRaises(ZeroDivisionError):  # the callable's exception, after the call
                ampath.preview(back, "png", width=400, progress=lambda f: 1 / 0)
        for name, fs in heard.items():
            self.assertTrue(fs, name)
            self.assertEqual(fs, sorted(fs), name)
            self.assertEqual(fs[-1], 1.0, name)

    def test_bad_width_and_empty_set_raise(self):
        with ampath.PathSet() as empty:
            with self.assertRaises(ampath.Error) as cm:
                ampath.preview(empty)
            self.assertEqual(cm.exception.message, "preview: no paths to draw")
            empty.add([(0, 0, 0, 0.5), (1, 0, 0, 0.5)])
            with self.assertRaises(ampath.Error) as cm:
                ampath.preview(empty, width=50)
            self.assertEqual(cm.exception.name, "AMP_ERR_RANGE")


if __name__ == "__main__":
    unittest.main()
