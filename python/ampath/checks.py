"""`ampath check` in Python: the same independent checkers over the library (tools/check_*.c), returning the
figures of the tool's `--json` as a dict, section for section and key for key (python/tests/test_check.py
compares them with the tool's output on the same inputs; only the "time_s" timings differ).

    res = ampath.check(ps, mesh="part.stl")          # coverage of the mesh's solid, gouge, strokes, support
    res["coverage"]["coverage_gap_mm"], res["support"]["unheld_paths"], res["ok"]

Sections: "coverage" (with a trivariate, or a mesh without layer), "gouge" (object paths), "strokes"
(planar paths; with mesh and layer also inside the layer polygons), "support" (when the paths have support
paths, or with support=True); each has "ran" and, when it ran, "ok"; "ok" says whether all passed.
"""

import ctypes
import math
import re
import time

from . import _lib as L
from ._lib import lib
from .core import Mesh, PathSet, Trivariate, _check, _err, _fail, _head, _hold

_DEG = 57.295779513082320876
_ERR_CHECK = -10
_GOUGE_TOL = -5e-7  # AMP_GOUGE_TOL
_OUTSIDE_TOL = 0.01  # tools/check_mesh.c: vertices farther outside the mesh fail


def _vec(v):
    return [v.x, v.y, v.z]


def _verts_of(ps, i):
    """Pointer to the first vertex of path @i (amp_pathset_path_verts, a static inline in C)."""
    return ctypes.cast(ctypes.addressof(ps._ps.verts.contents) + ps._ps.paths[i].first * ctypes.sizeof(L.amp_pvert),
                       ctypes.POINTER(L.amp_pvert))


def _object_paths(ps):
    """Coverage is a property of the object paths (tools/check_coverage.c): a copy without the support."""
    obj, err = PathSet(), _err()
    try:
        for i in range(ps._ps.npaths):
            p = ps._ps.paths[i]
            if p.role == 0:
                _check(lib.amp_pathset_add(obj._ref, 0, _verts_of(ps, i), p.n, ctypes.byref(err)), err)
    except BaseException:
        obj.close()
        raise
    return obj


def _eps_from_comment(ps):
    """The eps recorded by `ampath cover` (its eps), else by `ampath field` (its covering radius), in the file @ps
    was read from (tools/check_trivariate.c, check_eps_from_comment), or 0."""
    src = getattr(ps, "source", None)
    text = "".join("# %s\n" % h for h in getattr(ps, "history", []))  # the stages' lines, as the file would hold
    if src and not text:
        try:
            with open(src, "rb") as f:
                text = f.read().decode("utf-8", "replace")
        except OSError:
            return 0.0
    for tag in ("cover", "field"):
        for m in re.finditer(r"# ampath " + tag + r"[^\n]*? eps ([-+0-9.eE]+)", text):
            try:
                eps = float(m.group(1))
            except ValueError:
                eps = 0.0
            if eps > 0:
                return eps
            break
    return 0.0


def _trivariate_eps(ps, obj, eps):
    """The allowed gap and where it came from, as tools/check_trivariate.c and tools/check_mesh.c pick them."""
    eps_from = "--eps"
    if eps is None:
        eps, eps_from = _eps_from_comment(ps), "path file"
        if not eps > 0:
            eps_from = "largest radius"
            eps = max([obj._ps.verts[k].r for k in range(obj._ps.nverts)] + [0.0])
    return eps, eps_from


def _measure(obj, dom, samples, seed):
    """amp_check_coverage of the object paths over @dom (a trivariate or a mesh BVH)."""
    g, err = L.new(L.amp_coverage), _err()
    _check(lib.amp_check_coverage(obj._ref, ctypes.byref(dom), samples, seed, ctypes.byref(g), ctypes.byref(err)),
           err)
    return g


def _run_trivariate(ps, obj, v, eps, samples, seed):
    eps, eps_from = _trivariate_eps(ps, obj, eps)
    v._live()
    g = _measure(obj, L.amp_coverage_domain(ctypes.pointer(v._s), None, 0.0), samples, seed)
    return {"ran": True, "ok": g.gap <= eps, "model": "trivariate", "eps": eps, "eps_from": eps_from,
            "coverage_gap_mm": g.gap, "samples": g.samples, "worst_point": _vec(g.worst),
            "worst_parameters": list(g.worst_par), "volume_mm3": g.volume,
            "deposited_mm3": lib.amp_pathset_volume(obj._ref, 0),
            "over_coverage": lib.amp_over_coverage(obj._ref, g.volume)}


def _run_mesh(ps, obj, m, eps, samples, seed, tol):
    b = m.bvh()
    worst_out, outside, rmax = 0.0, 0, 0.0
    verts = obj._ps.verts
    for k in range(obj._ps.nverts):
        p, r = verts[k].p, verts[k].r
        rmax = r if r > rmax else rmax
        if not lib.amp_bvh_inside(b, p):
            d = lib.amp_bvh_closest(b, p, None, None)
            worst_out = d if d > worst_out else worst_out
            outside += d > max(_OUTSIDE_TOL, tol)
    eps, eps_from = _trivariate_eps(ps, obj, eps)  # the covering's recorded claim, else the largest radius
    g = _measure(obj, L.amp_coverage_domain(None, ctypes.cast(b, ctypes.c_void_p), 0.0), samples, seed)
    vol = lib.amp_mesh_volume(m._ref)
    return {"ran": True, "ok": g.gap <= eps and outside == 0, "model": "mesh", "eps": eps, "eps_from": eps_from,
            "coverage_gap_mm": g.gap, "coverage_gap_mean_mm": g.mean, "samples": samples,
            "vertices_outside": outside, "worst_outside_mm": worst_out, "volume_mm3": vol,
            "deposited_mm3": lib.amp_pathset_volume(obj._ref, 0), "over_coverage": lib.amp_over_coverage(obj._ref, vol)}


def _coverage(ps, trivariate, mesh, layer, eps, samples, seed, tol):
    if trivariate is None and (mesh is None or layer is not None):
        why = "--layer given: the mesh is used for the stroke check" if mesh is not None else \
            "no model (--trivariate or --mesh)"
        return {"ran": False, "reason": why}
    if not any(ps._ps.paths[i].role == 0 and ps._ps.paths[i].n > 1 for i in range(ps._ps.npaths)):
        return {"ran": True, "ok": False, "reason": "no object path with a segment"}
    with _object_paths(ps) as obj:
        if trivariate is not None:
            return _run_trivariate(ps, obj, trivariate, eps, samples, seed)
        return _run_mesh(ps, obj, mesh, eps, samples, seed, tol)


def _gouge(ps, head):
    n = ps._ps.npaths
    if not any(ps._ps.paths[i].role == 0 for i in range(n)):
        return {"ran": False, "reason": "no object paths"}
    nseg = sum(p.n - 1 if p.n > 1 else p.n for p in (ps._ps.paths[i] for i in range(n)))
    v, err = L.new(L.amp_gouge_violation), _err()
    t0 = time.perf_counter()
    # every path counts, support included: the head must not hit support printed earlier either
    st = lib.amp_check_gouge(ps._ref, ctypes.byref(head), 0, _GOUGE_TOL, ctypes.byref(v), ctypes.byref(err))
    if st not in (0, _ERR_CHECK):
        _check(st, err)
    if not L.intact(v):
        raise L.stale(L.amp_gouge_violation, "amp_check_gouge")
    res = {"ran": True, "ok": st == 0, "paths": n, "segments": nseg, "method": "pairwise" if nseg < 2000 else "grid",
           "z_offs": head.z_offs, "theta_deg": head.theta * _DEG, "tolerance": _GOUGE_TOL}
    if st:
        res["violation"] = {"earlier_path": v.earlier_path, "earlier_segment": v.earlier_seg,
                            "later_path": v.later_path, "later_segment": v.later_seg,
                            "earlier_point": _vec(v.earlier_point), "later_point": _vec(v.later_point),
                            "depth": v.depth}
        res["message"] = err.msg.decode("utf-8", "replace")  # the tool's stderr line
    res["time_s"] = time.perf_counter() - t0
    return res


def _planar(ps, i):
    """A path on one height: a layer's stroke or a flat support row."""
    p = ps._ps.paths[i]
    v = ps._ps.verts
    return p.n > 0 and all(abs(v[k].p.z - v[p.first].p.z) <= 1e-9 for k in range(p.first + 1, p.first + p.n))


def _stroke(ps, i):
    """A layer's stroke: a planar object path (support paths lie outside the section and print no layer)."""
    return ps._ps.paths[i].role == 0 and _planar(ps, i)


def _layer_index(sl, z):
    for i in range(sl._sl.nlayers):
        lay = sl._sl.layers[i]
        if abs(lay.z_print - z) < 1e-6 or abs(lay.z_cut - z) < 1e-6:
            return i
    return None


def _layer_at(sl, z):
    i = _layer_index(sl, z)
    return None if i is None else ctypes.pointer(sl._sl.layers[i].polys)


def _printable_section(P, r):
    """Some island of 1e-3 mm2 or more, a box diagonal of r/2 or more and a mean half-width (area / boundary
    length) of r/16 or more, as the tool asks (a sliver or a speck has no centre line a bead could follow)."""
    isl = {}
    for i in range(P.nrings):
        ring = P.rings[i]
        pts = [P.pts[ring.first + q] for q in range(ring.n)]
        a = 0.5 * sum(pts[q].x * pts[(q + 1) % ring.n].y - pts[(q + 1) % ring.n].x * pts[q].y for q in range(ring.n))
        ln = sum(math.hypot(pts[(q + 1) % ring.n].x - pts[q].x, pts[(q + 1) % ring.n].y - pts[q].y)
                 for q in range(ring.n))
        f = isl.setdefault(ring.island, [0.0, 0.0, math.inf, math.inf, -math.inf, -math.inf])
        f[0] += a
        f[1] += ln
        for p in pts:
            f[2], f[3], f[4], f[5] = min(f[2], p.x), min(f[3], p.y), max(f[4], p.x), max(f[5], p.y)
    return any(a >= 1e-3 and math.hypot(x1 - x0, y1 - y0) >= 0.5 * r and a >= ln * r / 16
               for a, ln, x0, y0, x1, y1 in isl.values())


def _layers_without_paths(ps, sl, strokes):
    """Layers with a printable section (for the widest bead of the strokes) but no stroke at their height, as
    the tool counts them."""
    v = ps._ps.verts
    r = max((v[k].r for i in strokes for k in range(ps._ps.paths[i].first, ps._ps.paths[i].first + ps._ps.paths[i].n)),
            default=0.0)
    printed = {_layer_index(sl, v[ps._ps.paths[i].first].p.z) for i in strokes}
    return sum(1 for li in range(sl._sl.nlayers)
               if li not in printed and _printable_section(sl._sl.layers[li].polys, r))


def _strokes(ps, sl, tol):
    planar = [i for i in range(ps._ps.npaths) if _planar(ps, i)]
    strokes = [i for i in planar if _stroke(ps, i)]
    if not strokes and sl is not None:
        return {"ran": True, "ok": False, "reason": "no planar paths: nothing prints the layers of the mesh"}
    if not planar:
        return {"ran": False, "reason": "no planar paths"}
    tot = dict(segments=0, pseudo=0, crossings=0, repeated_edges=0, outside=0)
    failed = nolayer = 0
    for i in planar:
        region = None
        if sl is not None and _stroke(ps, i):
            region = _layer_at(sl, ps._ps.verts[ps._ps.paths[i].first].p.z)
            nolayer += region is None
        rep, err = L.new(L.amp_stroke_report), _err()
        st = lib.amp_check_path_stroke(ps._ref, i, region, tol, ctypes.byref(rep), ctypes.byref(err))
        if st == -2:  # AMP_ERR_NOMEM
            _check(st, err)
        if not L.intact(rep):
            raise L.stale(L.amp_stroke_report, "amp_check_path_stroke")
        failed += st != 0
        for k in tot:
            tot[k] += getattr(rep, k)
    missing = _layers_without_paths(ps, sl, strokes) if sl is not None else 0
    return {"ran": True, "ok": failed == 0 and nolayer == 0 and missing == 0, "paths": len(planar),
            "segments": tot["segments"], "pseudo_segments": tot["pseudo"], "crossings": tot["crossings"],
            "repeated_edges": tot["repeated_edges"], "outside": tot["outside"], "paths_without_layer": nolayer,
            "layers_without_paths": missing, "failed_paths": failed}


def _support(ps, required, overhang, max_gap, bridge):
    roles = [ps._ps.paths[i].role for i in range(ps._ps.npaths)]
    if 0 not in roles:
        return {"ran": False, "reason": "no object paths"}
    if 1 not in roles and not required:
        return {"ran": False, "reason": "no support paths (--support requires every object path to be held)"}
    o, r, err = L.new(L.amp_hold_opts), L.new(L.amp_hold_report), _err()
    lib.amp_hold_opts_default(ctypes.byref(o))
    o.overhang, o.max_gap, o.bridge = overhang, max_gap, bridge
    t0 = time.perf_counter()
    try:
        _check(lib.amp_check_hold(ps._ref, ctypes.byref(o), ctypes.byref(r), ctypes.byref(err)), err)
        if not (L.intact(r) and L.intact(o)):
            raise L.stale(L.amp_hold_report, "amp_check_hold")
        res = {"ran": True, "ok": r.failures == 0, "overhang_deg": o.overhang * _DEG, "max_gap_mm": o.max_gap,
               "bridge_mm": o.bridge, "step_mm": o.step, "samples": r.samples, "unheld_samples": r.unheld,
               "bridges": r.bridges, "bridged_mm": r.bridged_mm, "tips": r.tips, "failures": r.failures,
               "unheld_mm": r.failed_mm, "unheld_paths": r.npaths_failed,
               "unheld_path_list": [r.paths_failed[i] for i in range(min(r.npaths_failed, 100))]}
        if r.failures:
            res.update(worst_path=r.worst_path, worst_mm=r.worst_mm, worst_at=_vec(r.worst_at))
    finally:
        lib.amp_hold_report_free(ctypes.byref(r))
    res["time_s"] = time.perf_counter() - t0
    return res


_NAMES = ("coverage", "gouge", "strokes", "support")


def _validate(trivariate, mesh, layer, first_layer, eps, samples, tol, overhang_deg, max_gap, bridge, skip):
    """cmd_check.c's checks of its options, with its messages (Error AMP_ERR_ARG)."""
    if trivariate is not None and mesh is not None:
        _fail("give either trivariate or mesh, not both")
    if eps is not None and not eps > 0:
        _fail("eps must be positive (got %g)" % eps)
    if not (isinstance(samples, int) and 1 <= samples <= 100000000):
        _fail("samples must be in 1..100000000")
    if layer is not None and not (layer > 0 and math.isfinite(layer)):
        _fail("layer must be positive (got %g)" % layer)
    if layer is not None and mesh is None:
        _fail("layer needs the mesh that was sliced")
    if not (first_layer >= 0 and math.isfinite(first_layer)):
        _fail("first_layer must be a positive height in mm")
    if not (0.0 <= tol <= 1e3):
        _fail("tol must be in [0, 1000] mm")
    if not (0.0 <= overhang_deg < 90.0):
        _fail("overhang must be in [0, 90) degrees (got %g)" % overhang_deg)
    if not (0.0 <= max_gap <= 1e3) or not (0.0 <= bridge <= 1e4):
        _fail("max_gap and bridge must be >= 0 mm")
    unknown = set(skip) - set(_NAMES)
    if unknown:
        _fail("skip: unknown checks %s (known: %s)" % (", ".join(sorted(unknown)), ", ".join(_NAMES)))


def check(paths, trivariate=None, mesh=None, layer=None, first_layer=0.0, z_offs=0.5, theta_deg=72.0, eps=None,
          samples=20000, seed=1, tol=1e-6, support=False, overhang_deg=45.0, max_gap=1.0, bridge=5.0, skip=()):
    """`ampath check PATHS [--trivariate T | --mesh M [--layer H]] ... --json` as a dict (see the module).
    @paths: a PathSet, or a `.amp` file name. @trivariate: a Trivariate, a built-in name or a `.spl` file;
    @mesh: a Mesh or an `.stl` file (with @layer, the mesh the paths were sliced from at that height,
    @first_layer as the tool's --first-layer). @eps: the allowed gap (default: the eps `ampath cover`
    or the covering radius `ampath field` recorded in the file @paths was read from, else the largest vertex
    radius). @skip: names of checks not
    to run (the tool's --no-NAME). @support: run the support check even without support paths.
    Bad options raise Error (AMP_ERR_ARG); a failed check is not an exception: its section has "ok": False."""
    skip = (skip,) if isinstance(skip, str) else tuple(skip)
    _validate(trivariate, mesh, layer, first_layer, eps, samples, tol, overhang_deg, max_gap, bridge, skip)
    head = _head(z_offs, theta_deg)
    own = []
    try:
        if not isinstance(paths, PathSet):
            paths = PathSet.read(paths)
            own.append(paths)
        if trivariate is not None and not isinstance(trivariate, Trivariate) and "coverage" not in skip:
            trivariate = Trivariate.load(trivariate)
            own.append(trivariate)
        if mesh is not None and not isinstance(mesh, Mesh) and "coverage" not in skip and layer is None:
            mesh = Mesh.load(mesh)
            own.append(mesh)
        with _hold(paths, trivariate, mesh):
            return _run_all(paths, trivariate, mesh, layer, first_layer, head, eps, samples, seed, tol, support,
                            overhang_deg / _DEG, max_gap, bridge, skip)
    finally:
        for o in own:
            o.close()


def _slices_for(mesh, layer, first_layer):
    """The layers the strokes are checked against, from a copy of the mesh (slicing orients it; the caller's
    Mesh stays as it is): a Mesh passes through its binary STL, exact for a mesh read from one."""
    from .pipeline import Slices
    if isinstance(mesh, Mesh):
        with Mesh.from_stl_bytes(mesh.to_stl()) as m:
            return Slices(m, layer, first_layer)
    with Mesh.load(mesh) as m:
        return Slices(m, layer, first_layer)


def _run_all(paths, trivariate, mesh, layer, first_layer, head, eps, samples, seed, tol, support, overhang,
             max_gap, bridge, skip):
    res = {}
    for name in _NAMES:
        if name in skip:
            res[name] = {"ran": False, "reason": "skipped on request"}
        elif name == "coverage":  # (skipped, an unloaded model is not looked at)
            res[name] = _coverage(paths, trivariate, mesh, layer, eps, samples, seed, tol)
        elif name == "gouge":
            res[name] = _gouge(paths, head)
        elif name == "strokes":
            if layer is not None and any(_planar(paths, i) for i in range(paths._ps.npaths)):
                with _slices_for(mesh, layer, first_layer) as sl:
                    res[name] = _strokes(paths, sl, tol)
            else:
                res[name] = _strokes(paths, None, tol)
        else:
            res[name] = _support(paths, support, overhang, max_gap, bridge)
    res["ok"] = all(s.get("ok", True) for s in res.values())
    return res
