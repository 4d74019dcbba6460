"""Pictures of path sets (docs/interfaces.md §4 `ampath preview`), drawn by the library's renderer (ampath/preview.h):
the same bytes as the tool."""

import ctypes
import os

from . import _lib as L
from ._lib import lib
from .core import _Progress, _fail, _hold, _to_buf, _todict, _write_bytes


def preview(paths, format="png", width=1600, output=None, stats=None, progress=None):
    """A PNG or SVG picture of @paths (isometric and top views, tubes scaled by the deposition radius,
    coloured by print order). Returns the bytes; with @output the file is also written (replaced safely),
    and the format follows its extension when it ends in .png or .svg. A dict passed as @stats receives
    the figures (width, height, paths, support, vertices, drawn, bytes). @progress (a callable taking the
    fraction done) hears of the drawing."""
    if output is not None:
        ext = os.path.splitext(str(output))[1].lower()
        if ext in (".png", ".svg"):
            format = ext[1:]
    if format not in ("png", "svg"):
        _fail("format must be 'png' or 'svg'")
    if "amp_preview_png" in L.MISSING:
        _fail("%s has no preview renderer (ampath/preview.h): a newer libampath is needed" % L.LIBRARY_PATH, -9)
    st = L.new(L.amp_preview_stats)
    if progress is not None and "amp_preview_png_opts" not in L.MISSING:
        fn = lib.amp_preview_png_opts if format == "png" else lib.amp_preview_svg_opts
        pr = _Progress(progress)
        o = L.amp_preview_opts(int(width), pr.c, None)
        with _hold(paths):
            data = _to_buf(lambda sink, buf, err: fn(paths._ref, ctypes.byref(o), sink, buf, ctypes.byref(st), err))
        pr.done()
    else:
        fn = lib.amp_preview_png if format == "png" else lib.amp_preview_svg
        with _hold(paths):
            data = _to_buf(lambda sink, buf, err: fn(paths._ref, int(width), sink, buf, ctypes.byref(st), err))
    if output is not None:
        _write_bytes(output, data)
    if stats is not None:
        stats.update(_todict(st))
    return data

