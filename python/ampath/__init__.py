"""ampath — print paths for additive manufacturing, over libampath (ctypes; no compiler needed).

    import ampath
    with ampath.Trivariate.model("helix") as v:
        ps = ampath.cover(v, eps=1, dir="u")
    job = ampath.gcode(ampath.mdr(ampath.order(ps)), printer="generic")
    print(job.stats["time"], len(job.text))

Every failure raises ampath.Error (.status, .name, .message: the library's message).
See README.md "Using ampath from Python".
"""

from ._lib import LIBRARY_PATH
from .core import Error, Mesh, Path, PathSet, Trivariate, mesh_names, trivariate_names
from .checks import check
from .pipeline import (GCode, Printer, Slices, cover, coverage_gap, field, gcode, mdr, order, printer_names,
                       slice, support)
from .preview import preview
from .bridge import BridgeClient, BridgeError

__version__ = "0.1.0"
__all__ = ["Error", "Mesh", "Path", "PathSet", "Trivariate", "mesh_names", "trivariate_names", "GCode", "Printer",
           "Slices", "check", "cover", "coverage_gap", "field", "gcode", "mdr", "order", "printer_names", "slice",
           "support", "preview", "BridgeClient", "BridgeError", "LIBRARY_PATH"]
