"""The pipeline stages over libampath, each doing what the matching `ampath` command does with the library,
so that the bytes written are the tool's (python/tests/test_pipeline.py proves it).

Options are keyword arguments named after the fields of the C options structs (amp_cover_opts,
amp_order_opts, amp_mdr_opts, amp_support_opts, amp_contpath_opts, amp_field_opts, amp_gcode_opts), on top
of the library's defaults; the head is given as z_offs (mm) and theta_deg (degrees, as the tool takes it).
Every stage returns a new PathSet whose .stats dict holds the library's figures.
"""

import ctypes
import math
import warnings

from . import _lib as L
from ._lib import lib
from .core import (Error, Mesh, PathSet, Trivariate, _apply, _b, _check, _derive, _err, _fail, _head, _hold,
                   _Owner, _Progress, _todict)

_DIRS = {"u": 0, "v": 1, "w": 2, 0: 0, 1: 1, 2: 2}


def _dir(d):
    if d not in _DIRS:
        _fail("dir must be u, v or w, got %r" % (d,))
    return _DIRS[d]


def _dir_or_auto(d):
    return -1 if d == "auto" else _dir(d)  # -1: AMP_COVER_AUTO / AMP_FIELD_AUTO


def _run(fn, out, progress=None, inputs=()):
    """Call a stage that appends to @out, holding its @inputs; free @out on failure."""
    try:
        with _hold(*inputs):
            fn()
        if progress is not None:
            progress.done()
    except BaseException:
        out.close()
        raise
    return out


def cover(trivariate, eps, dir="auto", measure="arclen", progress=None, max_curves=1e6, max_length=5e7, **opts):
    """Paper 1 §4.1 (`ampath cover`): paths covering @trivariate within @eps mm.
    Options: dir (auto|u|v|w; auto: the direction whose curves are the most level), min_depth, measure (arclen|iso), radius, chord_tol, cells, max_depth.
    As the tool, a covering estimated (amp_cover_estimate) above @max_curves curves or @max_length mm of paths is
    refused before it starts (ampath.Error AMP_ERR_LIMIT): a small eps grows the work without bound."""
    o = L.amp_cover_opts()
    lib.amp_cover_opts_default(ctypes.byref(o))
    o.eps = eps
    o.dir = _dir_or_auto(dir)
    if measure not in ("arclen", "iso"):
        _fail("measure must be arclen or iso")
    o.measure = 0 if measure == "arclen" else 1
    _apply(o, opts, "cover", skip=("eps", "dir", "measure"))
    curves, length, err = ctypes.c_double(), ctypes.c_double(), _err()
    with _hold(trivariate):
        trivariate._live()
        _check(lib.amp_cover_estimate(trivariate._ref, ctypes.byref(o), ctypes.byref(curves), ctypes.byref(length),
                                      ctypes.byref(err)), err)
    for n, limit, what, opt in ((curves.value, max_curves, "covering curves", "max_curves"),
                                (length.value, max_length, "mm of paths", "max_length")):
        if not n <= limit:
            err.msg = ("refused: about %.3g %s estimated, more than the limit of %.3g (raise it with %s=N)"
                       % (n, what, limit, opt)).encode()
            _check(-7, err)
    pr = _Progress(progress)
    o.progress = pr.c
    out, st, err = PathSet(), L.new(L.amp_cover_stats), _err()

    def go():
        _check(lib.amp_cover_trivariate(trivariate._ref, ctypes.byref(o), out._ref, ctypes.byref(st),
                                        ctypes.byref(err)), err)
        out.stats = _todict(st)
        out.stats["dir"] = "uvw"[out.stats["dir"]]
        _derive(out, "ampath cover %s: eps %.17g measure %s dir %s min-depth %d"
                % (getattr(trivariate, "name", None) or "trivariate", eps, measure, out.stats["dir"], o.min_depth),
                None)
    return _run(go, out, pr, (trivariate,))


def coverage_gap(trivariate, paths, samples=20000, seed=1):
    """Independent coverage measurement (amp_check_coverage over a trivariate) as a dict."""
    g, err = L.new(L.amp_coverage), _err()
    with _hold(trivariate, paths):
        trivariate._live()
        dom = L.amp_coverage_domain(ctypes.pointer(trivariate._s), None, 0.0)
        _check(lib.amp_check_coverage(paths._ref, ctypes.byref(dom), samples, seed, ctypes.byref(g),
                                      ctypes.byref(err)), err)
    d = _todict(g)
    d["over_coverage"] = g.deposited / g.volume if g.volume > 0 else 0.0
    return d


def _regions(regions, loaded):
    """Region meshes (Mesh objects or `.stl` names) for amp_field_opts.within/without; the ones loaded here
    are appended to @loaded (the caller closes them)."""
    out = []
    for r in regions:
        if not isinstance(r, Mesh):
            r = Mesh.load(r)
            loaded.append(r)
        out.append(r)
    return out


def _spine_points(along):
    """The sweep spine: a PathSet or `.amp` file (its first path, as the tool's --along) or a sequence of
    (x, y, z[, r]) points (or an (n, 3|4) NumPy array)."""
    if isinstance(along, (str, bytes)) or hasattr(along, "__fspath__"):
        with PathSet.read(along) as ps:
            return [p[:3] for p in ps[0].points] if len(ps) else []
    if isinstance(along, PathSet):
        return [p[:3] for p in along[0].points] if len(along) else []
    return [tuple(p[:3]) for p in (along.tolist() if hasattr(along, "tolist") else along)]


def _field_of(field, mesh, dir, along, side, f, err):
    """Fill the amp_field @f as cmd_field.c does; returns what must outlive the call (sweep, trivariate)."""
    if isinstance(field, Trivariate):
        _check(lib.amp_field_from_spline(ctypes.byref(f), field._ref, _dir_or_auto(dir), ctypes.byref(err)), err)
        return [field]
    if (field == "sweep") != (along is not None):
        _fail("along (the spine) goes with field 'sweep' (and is required by it)")
    if field == "sweep":
        pts = _spine_points(along)
        arr = (L.amp_vec3 * max(1, len(pts)))(*[L.amp_vec3(*p) for p in pts])
        sw = L.new(L.amp_sweep)  # about 25 KB of caller memory the field points into
        _check(lib.amp_field_sweep(ctypes.byref(f), ctypes.byref(sw), arr, len(pts), side, ctypes.byref(err)), err)
        return [sw]
    if field in ("helix-square", "box"):
        _check(lib.amp_field_builtin(ctypes.byref(f), _b(field), lib.amp_mesh_bbox(mesh._ref), ctypes.byref(err)),
               err)
        return []
    t = Trivariate.load(field)  # a .spl file or a built-in trivariate name, as the tool
    try:
        _check(lib.amp_field_from_spline(ctypes.byref(f), t._ref, _dir_or_auto(dir), ctypes.byref(err)), err)
    except BaseException:
        t.close()
        raise
    return [t]


def field(mesh, field, spacing=1.0, pattern="grid", dir="auto", along=None, side=6.0, within=None, without=(),
          progress=None, **opts):
    """Paper 1 §4.2 (`ampath field`): curves of a direction field clipped to @mesh. @field: "helix-square",
    "box", "sweep" (a square of side @side mm swept along the spine @along: a PathSet or `.amp` file, its
    first path, or a sequence of points; paper Fig. 6), a Trivariate, or a built-in trivariate name or `.spl`
    file (curves along @dir: u, v, w, or "auto" for the most level ones). @within: cover only the part inside this closed region (a Mesh or `.stl`);
    @without: a region or a list of regions whose parts other fields cover (the tool's --within/--without).
    Options: step, min_len, radius, shells (amp_field_opts). @progress: a callable taking the fraction done."""
    f, o, st, err = L.amp_field(), L.amp_field_opts(), L.new(L.amp_field_stats), _err()
    if pattern not in ("grid", "hex"):
        _fail("pattern must be grid or hex")
    lib.amp_field_opts_default(ctypes.byref(o))
    o.spacing = spacing
    o.pattern = 0 if pattern == "grid" else 1
    _apply(o, opts, "field", skip=("spacing", "pattern", "within", "without", "nwithout"))
    pr = _Progress(progress)
    o.progress = pr.c
    if without is None or isinstance(without, (Mesh, str, bytes)) or hasattr(without, "__fspath__"):
        without = [] if without is None else [without]
    loaded, out, keep = [], PathSet(), []
    try:
        keep = _field_of(field, mesh, dir, along, side, f, err)
        if not isinstance(field, Trivariate):
            loaded += [k for k in keep if isinstance(k, Trivariate)]  # loaded by name here: closed below
        regions = _regions(([within] if within is not None else []) + list(without), loaded)
        with _hold(*regions):
            bvhs = [r.bvh() for r in regions]
            if within is not None:
                o.within = bvhs.pop(0)
            arr = (ctypes.c_void_p * max(1, len(bvhs)))(*bvhs)
            o.without, o.nwithout = (ctypes.cast(arr, ctypes.c_void_p), len(bvhs)) if bvhs else (None, 0)

            def go():
                _check(lib.amp_field_cover(ctypes.byref(f), mesh.bvh(), ctypes.byref(o), out._ref, ctypes.byref(st),
                                           ctypes.byref(err)), err)
                out.stats = _todict(st)
                _derive(out, "ampath field: direction-field curves clipped to the mesh, eps %.10g (covering radius)"
                        % st.target, None)
            _run(go, out, pr, [mesh] + [k for k in keep if isinstance(k, Trivariate)])
        del arr
    except BaseException:
        out.close()
        raise
    finally:
        for m in loaded:
            m.close()
    return out


def order(paths, z_offs=0.5, theta_deg=72.0, improve=True, progress=None, **opts):
    """Paper 1 §5.1 (`ampath order`): a gouge-free print order (Algorithm 2; improve=False: plain greedy).
    Options: lookahead, merge_window (amp_order_opts)."""
    o = L.amp_order_opts()
    lib.amp_order_opts_default(ctypes.byref(o))
    o.head = _head(z_offs, theta_deg)
    o.improve = 1 if improve else 0
    _apply(o, opts, "order", skip=("head", "improve"))
    pr = _Progress(progress)
    o.progress = pr.c
    out, st, err = PathSet(), L.new(L.amp_order_stats), _err()

    def go():
        _check(lib.amp_order(paths._ref, ctypes.byref(o), out._ref, ctypes.byref(st), ctypes.byref(err)), err)
        out.stats = _todict(st)
        _derive(out, "ampath order: z_offs %g mm, theta %g deg, %s, %d subdivisions"
                % (z_offs, theta_deg, "improved" if improve else "plain greedy", st.subdivisions), paths)
    return _run(go, out, pr, (paths,))


def mdr(paths, nominal=0.5, progress=None, **opts):
    """Paper 1 §5.2 (`ampath mdr`): deposition radius per vertex. Options: r_min, r_max, fragment."""
    o = L.amp_mdr_opts()
    lib.amp_mdr_opts_default(ctypes.byref(o), nominal)
    _apply(o, opts, "mdr", skip=("nominal",))
    pr = _Progress(progress)
    o.progress = pr.c
    out, st, err = PathSet(), L.new(L.amp_mdr_stats), _err()

    def go():
        _check(lib.amp_mdr(paths._ref, ctypes.byref(o), out._ref, ctypes.byref(st), ctypes.byref(err)), err)
        out.stats = _todict(st)
        _derive(out, "ampath mdr", paths)
    return _run(go, out, pr, (paths,))


def support(paths, mesh, z_offs=0.5, theta_deg=72.0, progress=None, pads=True, **opts):
    """Paper 1 §5.3 (`ampath support`): support under @mesh (a Mesh, or a Trivariate whose boundary is
    tessellated as the tool does), interleaved in print order, with pads under the object beads the rows
    leave in the air (@pads=False: the rows only, as `--no-pads`). Options: spacing, layer_height, radius,
    min_gap (amp_support_opts)."""
    if isinstance(mesh, Trivariate):
        with Mesh.from_trivariate(mesh) as m:
            return support(paths, m, z_offs, theta_deg, progress, pads, **opts)
    if isinstance(mesh, (str, bytes)) or hasattr(mesh, "__fspath__"):  # a file name, as check and field take
        with Mesh.load(mesh) as m:
            return support(paths, m, z_offs, theta_deg, progress, pads, **opts)
    if not isinstance(mesh, Mesh):
        raise TypeError("support: mesh must be a Mesh, a Trivariate or an .stl file name, not %s"
                        % type(mesh).__name__)
    o = L.amp_support_opts()
    lib.amp_support_opts_default(ctypes.byref(o))
    o.head = _head(z_offs, theta_deg)
    _apply(o, opts, "support", skip=("head", "find_unheld"))
    # the pads' judge as the tool sets it: the library's own held-path check, called from C
    o.find_unheld = ctypes.cast(lib.amp_check_hold_runs, L.UNHELD_FN) if pads else L.UNHELD_FN()
    pr = _Progress(progress)
    o.progress = pr.c
    out, st, err = PathSet(), L.new(L.amp_support_stats), _err()

    def go():
        _check(lib.amp_support(paths._ref, mesh.bvh(), ctypes.byref(o), out._ref, ctypes.byref(st),
                               ctypes.byref(err)), err)
        out.stats = _todict(st)
        _derive(out, "ampath support", paths)
    return _run(go, out, pr, (paths, mesh))


# ---------------------------------------------------------------- slicing


class Slices(_Owner):
    """The layers of a sliced mesh (amp_slices), owned; .layers lists (z_cut, z_print, rings) per layer with
    rings as lists of (x, y) and a hole flag."""

    def __init__(self, mesh, layer, first_layer=0.0):
        super().__init__()
        self._sl = L.amp_slices()
        lib.amp_slices_init(ctypes.byref(self._sl), None)
        if not (layer > 0 and math.isfinite(layer)):
            self.close()
            _fail("layer must be a positive height in mm")
        self.layer = layer
        # the slicer chains segments by their direction: the orientation must agree (as the tool does)
        self.flipped = mesh.orient()
        o, err = L.amp_slice_opts(layer, first_layer), _err()
        with _hold(mesh):
            st = lib.amp_slice_mesh(mesh._ref, ctypes.byref(o), ctypes.byref(self._sl), ctypes.byref(err))
        if st:
            self.close()
        _check(st, err)

    def _release(self):
        lib.amp_slices_free(ctypes.byref(self._sl))

    def __len__(self):
        self._live()
        return self._sl.nlayers

    @property
    def open_chains(self):
        return self._sl.open_chains

    @property
    def gaps_closed(self):
        """Open section chains joined into rings across their gaps (an unclosed mesh), over all layers."""
        return self._sl.gaps_closed

    @property
    def overlapping_layers(self):
        """Layers whose rings overlapped (bodies exported without a boolean union), merged by the nonzero rule."""
        return self._sl.overlaps

    def _rings(self, i):
        self._live()
        P = self._sl.layers[i].polys
        for r in range(P.nrings):
            ring = P.rings[r]
            yield [(P.pts[k].x, P.pts[k].y) for k in range(ring.first, ring.first + ring.n)], bool(ring.hole)

    @property
    def layers(self):
        return [{"z_cut": self._sl.layers[i].z_cut, "z_print": self._sl.layers[i].z_print,
                 "rings": [{"points": pts, "hole": hole} for pts, hole in self._rings(i)],
                 "area": lib.amp_polyset_area(ctypes.byref(self._sl.layers[i].polys))}
                for i in range(self._sl.nlayers)]

    def polygons(self, radius=0.5):
        """`ampath slice --polygons`: one closed path per ring (last vertex repeats the first) at the cutting
        height, radius @radius on every vertex."""
        ps = PathSet()
        for i in range(self._sl.nlayers):
            z = self._sl.layers[i].z_cut
            for pts, _hole in self._rings(i):
                ps.add([(x, y, z) for x, y in pts + pts[:1]], radius=radius)
        return ps

    def continuous(self, radius=None, grid="square", nozzle=None, printer=None, infill=None, tour="cycle-tree",
                   eps_c=1.0, **opts):
        """`ampath slice --continuous` (paper 2): per island the perimeter loops and one stroke over the Euler
        lattice, spliced into one closed stroke; every path is then checked (crossings, edges printed twice,
        points outside its layer) and a failure raises Error (AMP_ERR_CHECK), as the tool exits 1.
        The bead: @radius (default 0.225 mm), else 1.125 x @nozzle wide, else 1.125 x the nozzle of
        @printer (a Printer, built-in name or slicer .ini). @infill: sparse density in % (sets the cell as
        the tool's --infill), @tour: "cycle-tree" or "merge", @eps_c: overhang warning threshold (section
        2.1, in r; a RuntimeWarning as the tool's stderr warning). Other options are the fields of
        amp_contpath_opts: cell, offset, perimeters, support_stretches, support_corners, pseudo_edges,
        skin_bottom, skin_top, skin_cell, join, overlap_cap. .stats adds the tool's --json figures (extrusion_starts,
        crossings, repeated_edges, outside, failed_paths, overhang_mm, overhang_pairs, max_overhang_mm)."""
        o = _contpath_opts(_bead_radius(radius, nozzle, printer), grid, infill, tour, eps_c, opts)
        out, st, err = PathSet(), L.new(L.amp_contpath_stats), _err()
        verify = o.verify_stroke

        def layers(with_verifier):
            self._live()
            lib.amp_pathset_clear(out._ref)
            o.verify_stroke = verify if with_verifier else L.VERIFY_FN()  # NULL: no verifier
            _check(lib.amp_contpath_layers(ctypes.byref(self._sl), ctypes.byref(o), out._ref, ctypes.byref(st),
                                           ctypes.byref(err)), err)

        def go():
            # as the tool: the final check is the skin bands' safety net first; the per-island verifier (the same
            # check once more on most islands) runs only when a path fails it
            layers(False)
            checked = self._check_strokes(out, raise_on_failure=False)
            if checked["failed_paths"]:
                layers(True)
                checked = self._check_strokes(out)
            out.stats = _todict(st)
            out.stats.update(self._overhangs(eps_c, o.radius))
            out.stats.update(checked)
        return _run(go, out, None, (self,))

    def _overhangs(self, eps_c, r):
        """§2.1 per layer pair, as the tool: sampled every 4 r; the pairs beyond eps_c r warned about."""
        n = self._sl.nlayers
        per = [lib.amp_slices_overhang(ctypes.byref(self._sl), i, 4 * r) for i in range(n - 1)]
        over = sum(1 for v in per if v > eps_c * r)
        worst, at = 0.0, 0
        for i, v in enumerate(per):
            if v > worst:
                worst, at = v, i + 1
        if over:
            warnings.warn("%d layer pairs are not eps-continuous (overhang > %g r = %g mm; worst %.3g mm under layer "
                          "%d at z %.4g): the layer above may sag" % (over, eps_c, eps_c * r, worst, at,
                                                                      self._sl.layers[at].z_print),
                          RuntimeWarning, stacklevel=5)
        return {"eps_c": eps_c, "overhang_pairs": over, "max_overhang_mm": worst if worst < math.inf else -1,
                "overhang_mm": [v if v < math.inf else -1 for v in per],
                "open_chain_layers": [i for i in range(n) if self._sl.layers[i].open_chains]}

    def _region(self, z):
        for i in range(self._sl.nlayers):
            if abs(self._sl.layers[i].z_print - z) < 1e-9:
                return ctypes.pointer(self._sl.layers[i].polys)
        return None

    def _check_strokes(self, ps, raise_on_failure=True):
        """The tool's check of every path against its layer (tol 1e-6 mm); Error AMP_ERR_CHECK on a failure."""
        tot = dict(crossings=0, repeated_edges=0, outside=0, failed_paths=0)
        first = None
        for i in range(ps._ps.npaths):
            path = ps._ps.paths[i]
            reg = self._region(ps._ps.verts[path.first].p.z) if path.n else None
            rep, err = L.new(L.amp_stroke_report), _err()
            st = lib.amp_check_path_stroke(ps._ref, i, reg, 1e-6, ctypes.byref(rep), ctypes.byref(err))
            if not L.intact(rep):
                raise L.stale(L.amp_stroke_report, "amp_check_path_stroke")
            if st == -2:  # AMP_ERR_NOMEM
                _check(st, err)
            if st != 0:
                tot["failed_paths"] += 1
                if first is None:
                    first = "path %d fails its check: %s" % (i, err.msg.decode("utf-8", "replace"))
            for k in ("crossings", "repeated_edges", "outside"):
                tot[k] += getattr(rep, k)
        tot["extrusion_starts"] = _count_starts(ps)
        if tot["failed_paths"] and raise_on_failure:
            _fail("%s; %d paths fail the stroke check (%d crossings, %d edges printed twice, %d points outside "
                  "their layer): a bug, please report it" % (first, tot["failed_paths"], tot["crossings"],
                                                             tot["repeated_edges"], tot["outside"]), _ERR_CHECK)
        return tot


_ERR_CHECK = -10  # AMP_ERR_CHECK
_GRIDS = {"square": 0, "tri": 1, "hex": 2}
_TOURS = {"cycle-tree": 0, "merge": 1}


def _finite_pos(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 and math.isfinite(v)


def _bead_radius(radius, nozzle, printer):
    """The tool's bead: --radius, else --nozzle, else the --printer's nozzle (1.125 x wide), else 0.225 mm."""
    if radius is None and nozzle is None and printer is not None:
        pr = printer if isinstance(printer, Printer) else Printer(printer)
        nozzle = pr._p.nozzle_diameter
    if radius is None and nozzle is not None:
        if not _finite_pos(nozzle):
            _fail("nozzle must be positive")
        radius = 0.5 * 1.125 * nozzle  # a bead 1.125 x the nozzle wide, as slicers extrude
    if radius is None:
        radius = 0.225
    if not _finite_pos(radius):
        _fail("radius must be positive")
    return radius


def _contpath_opts(radius, grid, infill, tour, eps_c, opts):
    """amp_contpath_opts as cmd_slice.c fills them, with its checks and messages."""
    o = L.amp_contpath_opts()
    lib.amp_contpath_opts_default(ctypes.byref(o), radius)
    if grid not in _GRIDS:
        _fail("grid must be square, tri or hex, not '%s'" % (grid,))
    o.grid = _GRIDS[grid]
    for k in ("cell", "offset"):
        if k in opts and not _finite_pos(opts[k]):
            _fail("cell and offset must be positive")
    for k in ("skin_bottom", "skin_top"):
        if k in opts and not (isinstance(opts[k], (int, float)) and opts[k] >= 0 and math.isfinite(opts[k])):
            _fail("skin_bottom and skin_top must be thicknesses >= 0 mm")
    if not (isinstance(eps_c, (int, float)) and 0 < eps_c <= 1):
        _fail("eps_c must be in (0, 1]")
    _apply(o, opts, "continuous", skip=("radius", "grid", "tour", "verify_stroke"))
    # the skin bands' safety net as the tool sets it: the library's own checker, called from C
    o.verify_stroke = ctypes.cast(lib.amp_check_path_stroke, L.VERIFY_FN)
    if infill is not None and "cell" in opts and infill > 0:
        _fail("cell and infill exclude each other")
    if infill is not None and infill != 0:
        if not (isinstance(infill, (int, float)) and 0 < infill <= 100):
            _fail("infill must be a density in % (0 < P <= 100)")
        # every line of a square lattice of cell S carries two beads (a band 4r wide): x = 4r / S of the
        # area lies under the bands of one direction, 2x - x^2 under both; solved for the density
        o.cell = 4 * radius / (1 - math.sqrt(1 - infill / 100))
    if tour not in _TOURS:
        _fail("tour must be cycle-tree or merge, not '%s'" % (tour,))
    o.tour = _TOURS[tour]
    return o


def _count_starts(ps):
    """Extrusion starts as a G-code reader counts them (the tool's count_starts)."""
    starts = 0
    for i in range(ps._ps.npaths):
        path = ps._ps.paths[i]
        v = ps._ps.verts
        printing = False
        for k in range(path.first, path.first + path.n - 1):
            a, b = v[k], v[k + 1]
            dx, dy, dz = a.p.x - b.p.x, a.p.y - b.p.y, a.p.z - b.p.z
            moves = dx * dx + dy * dy + dz * dz > 0
            pr = (a.r > 0 or b.r > 0) and moves
            if pr and not printing:
                starts += 1
            if pr:
                printing = True
            elif moves:
                printing = False
    return starts


def slice(mesh, layer, first_layer=0.0, continuous=False, radius=None, nozzle=None, printer=None, **opts):
    """`ampath slice MESH --layer H (--polygons|--continuous)`: a PathSet of the layers. The radius of the
    polygons and the bead of the strokes: @radius, else 1.125 x @nozzle / 2, else from @printer's nozzle,
    else 0.225 mm (as the tool). Other options: those of Slices.continuous."""
    r = _bead_radius(radius, nozzle, printer)
    if not continuous and opts:
        raise TypeError("slice: options %s need continuous=True" % ", ".join(sorted(opts)))
    with Slices(mesh, layer, first_layer) as sl:
        return sl.continuous(r, **opts) if continuous else sl.polygons(r)


# ---------------------------------------------------------------- printers and G-code


def printer_names():
    return [lib.amp_printer_builtin_name(i).decode() for i in range(lib.amp_printer_builtin_count())]


class Printer:
    """A printer profile (amp_printer): a built-in name or a PrusaSlicer/SuperSlicer/OrcaSlicer `.ini`."""

    def __init__(self, spec="generic"):
        self._p, err = L.amp_printer(), _err()
        _check(lib.amp_printer_load(ctypes.byref(self._p), _b(spec), ctypes.byref(err)), err)

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        fields = {n for n, _ in L.amp_printer._fields_}
        if name not in fields:
            raise AttributeError(name)
        v = getattr(self._p, name)
        return v.decode() if isinstance(v, bytes) else v

    def bead_width(self):
        return lib.amp_printer_bead_width(ctypes.byref(self._p))

    def as_dict(self):
        return {n: getattr(self, n) for n, _ in L.amp_printer._fields_ if not n.endswith("_out") and n != "vars"}

    def variables(self):
        """Every key of the `.ini` (but start_gcode/end_gcode) with its value as written, for the macros."""
        raw = ctypes.string_at(ctypes.addressof(self._p) + L.amp_printer.vars.offset, self._p.vars_len)
        parts = raw.split(b"\0")[:-1]
        return {k.decode(): v.decode() for k, v in zip(parts[0::2], parts[1::2])}

    def __repr__(self):
        return "Printer(%r)" % self.name


class GCode:
    """A G-code job: .text (str, None when written to a file), .stats (dict of amp_gcode_stats), .printer."""

    def __init__(self, text, stats, printer):
        self.text, self.stats, self.printer = text, stats, printer

    def __str__(self):
        return self.text or ""


def _gcode_opts(printer, flavor, place, start_gcode, end_gcode, opts):
    pr = printer if isinstance(printer, Printer) else Printer(printer)
    o, err = L.amp_gcode_opts(), _err()
    _check(lib.amp_printer_gcode_opts(ctypes.byref(pr._p), ctypes.byref(o), ctypes.byref(err)), err)
    if flavor is not None:
        if flavor not in ("marlin", "klipper"):
            _fail("flavor must be marlin or klipper, got '%s'" % flavor)
        o.flavor = 1 if flavor == "klipper" else 0
        o.relative_e = o.flavor  # docs/interfaces.md §5: the flavour's E mode unless asked
    if place is None or place in ("center", "centre"):
        o.place = 0
    elif place == "origin":
        o.place = 1
    else:
        try:
            o.place_x, o.place_y = (float(c) for c in place)
        except (TypeError, ValueError):
            _fail("place must be 'center', 'origin' or (x, y) in mm, got %r" % (place,))
        o.place = 2
    keep = [pr]
    for name, text in (("start_gcode", start_gcode), ("end_gcode", end_gcode)):
        if text is not None:
            b = text.encode()
            keep.append(b)  # the writer reads the text during the call: keep the bytes alive
            setattr(o, name, b)
    _apply(o, opts, "gcode", skip=("profile", "start_gcode", "end_gcode", "place", "place_x", "place_y"))
    if flavor is not None and "junction_deviation" not in opts:  # the flavour's cornering, as the tool
        o.junction_deviation = lib.amp_gcode_junction_default(o.flavor, o.accel)
    return o, pr, keep


def gcode(paths, output=None, printer="generic", flavor=None, place=None, start_gcode=None, end_gcode=None,
          **opts):
    """`ampath gcode` (docs/interfaces.md §5): MDR-modulated G-code for @printer (a Printer, a built-in name or a slicer
    `.ini`), placed on its bed (@place: "center", "origin" or (x, y)). Other options are fields of
    amp_gcode_opts (print_feed, retract_length, z_hop, fan_speed, arcs, ...) overriding the profile's.
    With @output the file is written safely (replaced only after a complete write) and .text is None."""
    o, pr, keep = _gcode_opts(printer, flavor, place, start_gcode, end_gcode, opts)
    with _hold(paths):
        return _gcode_held(paths, output, o, pr, keep)


def _gcode_held(paths, output, o, pr, keep):
    st, err = L.new(L.amp_gcode_stats), _err()
    # the profile's start/end macros see the placed job, as in `ampath gcode` (the same bytes)
    _check(lib.amp_printer_gcode_job(ctypes.byref(pr._p), ctypes.byref(o), paths._ref, None, ctypes.byref(err)), err)
    if output is None:
        from .core import _to_buf
        data = _to_buf(lambda sink, buf, e: lib.amp_gcode_write(paths._ref, ctypes.byref(o), sink, buf,
                                                               ctypes.byref(st), e))
        text = data.decode()
    else:
        f = L.amp_out()
        _check(lib.amp_out_open(ctypes.byref(f), _b(output), ctypes.byref(err)), err)
        s = lib.amp_gcode_write(paths._ref, ctypes.byref(o), L.OUT_SINK, ctypes.cast(ctypes.byref(f),
                                ctypes.c_void_p), ctypes.byref(st), ctypes.byref(err))
        if s != 0:
            if f.werr:
                import os
                err.msg = ("%s: %s" % (f.target.decode(), os.strerror(f.werr))).encode()[:199]
                s = -5
            lib.amp_out_abort(ctypes.byref(f))
            _check(s, err)
        _check(lib.amp_out_commit(ctypes.byref(f), ctypes.byref(err)), err)
        text = None
    del keep
    return GCode(text, _todict(st), pr)


__all__ = ["cover", "coverage_gap", "field", "order", "mdr", "support", "Slices", "slice",
           "printer_names", "Printer", "GCode", "gcode", "Error"]
