"""Loading libampath and the ctypes mirror of its public structs and prototypes.

Only functions of the public headers (include/ampath/*.h) are used: the shared
library exports exactly those (a version script; tests/test_exports.c).

Every struct mirrored here is listed in STRUCTS with its C name, so that
python/tests/test_layout.py can compare each field's offset and each size with
what the C compiler says (run it after any header change: a mismatch names the
struct and field to fix).
"""

import ctypes
import ctypes.util
import os
import subprocess

from ctypes import (POINTER, Structure, c_char, c_char_p, c_double, c_int, c_long, c_size_t,
                    c_uint32, c_ulong, c_void_p)

# ---------------------------------------------------------------- finding the library


def _candidates():
    env = os.environ.get("AMPATH_LIBRARY")
    if env:
        yield env
        return
    try:
        libdir = subprocess.run(["pkg-config", "--variable=libdir", "ampath"], capture_output=True, text=True,
                                timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        libdir = ""
    if libdir:
        for name in ("libampath.so", "libampath.so.0"):
            yield os.path.join(libdir, name)
    here = os.path.dirname(os.path.abspath(__file__))
    yield os.path.normpath(os.path.join(here, "..", "..", "lib", "libampath.so"))
    found = ctypes.util.find_library("ampath")
    if found:
        yield found


def _load():
    tried = []
    for path in _candidates():
        if os.sep in path and not os.path.exists(path):
            tried.append(path + " (missing)")
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError("libampath.so not found; set AMPATH_LIBRARY to its path, install it (make install: "
                      "pkg-config ampath) or build the tree (make). Tried: " + "; ".join(tried or ["nothing"]))


lib, LIBRARY_PATH = _load()

# ---------------------------------------------------------------- structs (include/ampath/*.h)

PROGRESS_FN = ctypes.CFUNCTYPE(None, c_void_p, c_double)
SINK_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_void_p, c_size_t)

AMP_ERROR_MSG_SIZE = 200
AMP_PRINTER_NAME_MAX = 64
AMP_PRINTER_GCODE_MAX = 8192
AMP_PRINTER_UNKNOWN_MAX = 4096
AMP_PRINTER_VARS_MAX = 32768
AMP_OUT_PATH_MAX = 4096


class amp_error(Structure):
    _fields_ = [("status", c_int), ("line", c_long), ("offset", c_long), ("msg", c_char * AMP_ERROR_MSG_SIZE)]


class amp_vec3(Structure):
    _fields_ = [("x", c_double), ("y", c_double), ("z", c_double)]


class amp_box3(Structure):
    _fields_ = [("min", amp_vec3), ("max", amp_vec3)]


class amp_vec2(Structure):
    _fields_ = [("x", c_double), ("y", c_double)]


class amp_pvert(Structure):
    _fields_ = [("p", amp_vec3), ("r", c_double)]


class amp_path(Structure):
    _fields_ = [("role", c_int), ("first", c_size_t), ("n", c_size_t), ("h", c_double)]


class amp_pathset(Structure):
    _fields_ = [("alloc", c_void_p), ("paths", POINTER(amp_path)), ("npaths", c_size_t), ("cap_paths", c_size_t),
                ("verts", POINTER(amp_pvert)), ("nverts", c_size_t), ("cap_verts", c_size_t)]


class amp_buf(Structure):
    _fields_ = [("alloc", c_void_p), ("data", c_void_p), ("len", c_size_t), ("cap", c_size_t)]


class amp_out(Structure):
    _fields_ = [("f", c_void_p), ("direct", c_int), ("werr", c_int), ("target", c_char * AMP_OUT_PATH_MAX),
                ("tmp", c_char * AMP_OUT_PATH_MAX)]


class amp_spline(Structure):
    _fields_ = [("alloc", c_void_p), ("dim", c_int), ("rational", c_int), ("order", c_int * 3),
                ("count", c_size_t * 3), ("knots", POINTER(c_double) * 3), ("cp", POINTER(c_double)),
                ("ncp", c_size_t)]


class amp_tri(Structure):
    _fields_ = [("v", c_uint32 * 3)]


class amp_mesh(Structure):
    _fields_ = [("alloc", c_void_p), ("verts", POINTER(amp_vec3)), ("nverts", c_size_t), ("cap_verts", c_size_t),
                ("tris", POINTER(amp_tri)), ("ntris", c_size_t), ("cap_tris", c_size_t)]


class amp_stl_stats(Structure):
    _fields_ = [("binary", c_int), ("triangles", c_size_t), ("degenerate", c_size_t), ("vertices", c_size_t),
                ("duplicates", c_size_t), ("tjunctions", c_size_t),
                ("near_welded", c_size_t)]


class amp_head(Structure):
    _fields_ = [("z_offs", c_double), ("theta", c_double)]


class amp_cover_opts(Structure):
    _fields_ = [("eps", c_double), ("dir", c_int), ("min_depth", c_int), ("measure", c_int), ("radius", c_double),
                ("chord_tol", c_double), ("cells", c_int), ("max_depth", c_int), ("progress", PROGRESS_FN),
                ("progress_user", c_void_p)]


class amp_cover_stats(Structure):
    _fields_ = [("surfaces", c_size_t), ("curves", c_size_t), ("vertices", c_size_t), ("length", c_double),
                ("depth_limited", c_int), ("dir", c_int)]


class amp_coverage(Structure):
    _fields_ = [("gap", c_double), ("mean", c_double), ("worst", amp_vec3), ("worst_par", c_double * 3),
                ("samples", c_size_t), ("volume", c_double), ("deposited", c_double)]


class amp_coverage_domain(Structure):
    _fields_ = [("trivariate", POINTER(amp_spline)), ("mesh", c_void_p), ("margin", c_double)]


class amp_order_opts(Structure):
    _fields_ = [("head", amp_head), ("improve", c_int), ("lookahead", c_size_t), ("merge_window", c_size_t),
                ("nearest", c_int), ("travel_z_weight", c_double), ("progress", PROGRESS_FN),
                ("progress_user", c_void_p)]


class amp_order_stats(Structure):
    _fields_ = [(n, c_size_t) for n in ("paths_in", "fragments", "pieces", "subdivisions", "steps", "extended",
                                        "merges", "queries")]


class amp_mdr_opts(Structure):
    _fields_ = [("nominal", c_double), ("r_min", c_double), ("r_max", c_double), ("fragment", c_double),
                ("progress", PROGRESS_FN), ("progress_user", c_void_p)]


class amp_mdr_stats(Structure):
    _fields_ = [("fragments", c_size_t), ("pairs", c_size_t), ("at_min", c_size_t), ("at_max", c_size_t),
                ("isolated", c_size_t), ("r_lo", c_double), ("r_hi", c_double), ("deposited", c_double)]


# amp_support_unheld_fn (support.h): amp_check_hold_runs's signature (the run callback passed on as a pointer)
UNHELD_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_double, c_void_p, c_void_p, c_void_p)


class amp_support_opts(Structure):
    _fields_ = [("head", amp_head), ("spacing", c_double), ("layer_height", c_double), ("radius", c_double),
                ("min_gap", c_double), ("progress", PROGRESS_FN), ("progress_user", c_void_p),
                ("find_unheld", UNHELD_FN)]


class amp_support_stats(Structure):
    _fields_ = [("rays", c_size_t), ("columns", c_size_t), ("paths", c_size_t), ("length", c_double),
                ("unplaced", c_size_t), ("splits", c_size_t), ("conflicts", c_size_t), ("trimmed", c_double),
                ("settled", c_size_t), ("pads", c_size_t), ("pad_length", c_double), ("sliced", c_int), ("layer_height", c_double)]


class amp_ring(Structure):
    _fields_ = [("first", c_size_t), ("n", c_size_t), ("island", c_long), ("hole", c_int)]


class amp_polyset(Structure):
    _fields_ = [("alloc", c_void_p), ("pts", POINTER(amp_vec2)), ("npts", c_size_t), ("cap_pts", c_size_t),
                ("rings", POINTER(amp_ring)), ("nrings", c_size_t), ("cap_rings", c_size_t),
                ("nislands", c_size_t)]


class amp_slice_opts(Structure):
    _fields_ = [("layer", c_double), ("first_layer", c_double)]


class amp_layer(Structure):
    _fields_ = [("z_cut", c_double), ("z_print", c_double), ("polys", amp_polyset), ("open_chains", c_size_t)]


class amp_slices(Structure):
    _fields_ = [("alloc", c_void_p), ("layers", POINTER(amp_layer)), ("nlayers", c_size_t), ("z0", c_double),
                ("open_chains", c_size_t), ("nonmanifold", c_size_t), ("gaps_closed", c_size_t),
                ("overlaps", c_size_t)]


# amp_contpath_verify_fn (contpath.h): amp_check_path_stroke's signature; the stroke report is passed on as an
# opaque pointer (the mirror amp_stroke_report is defined below)
VERIFY_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_size_t, c_void_p, c_double, c_void_p, c_void_p)


class amp_contpath_opts(Structure):
    _fields_ = [("radius", c_double), ("cell", c_double), ("grid", c_int), ("offset", c_double),
                ("perimeters", c_int), ("support_stretches", c_int), ("support_corners", c_int),
                ("pseudo_edges", c_int), ("tour", c_int), ("skin_bottom", c_double), ("skin_top", c_double),
                ("skin_cell", c_double), ("join", c_int), ("verify_stroke", VERIFY_FN),
                ("progress", PROGRESS_FN), ("progress_user", c_void_p), ("overlap_cap", c_int)]


class amp_contpath_stats(Structure):
    _fields_ = ([(n, c_size_t) for n in ("layers", "empty_layers", "islands", "thin_islands", "dropped_islands",
                                         "island_strokes", "specks", "regions", "skin_regions", "strokes",
                                         "multi_stroke", "perimeter_loops", "support_paths", "travel_moves",
                                         "free_ends", "odd_vertices", "cycles", "tree_levels", "tour_fallbacks",
                                         "joins")]
                + [(n, c_double) for n in ("printed_length", "infill_length", "pseudo_length", "travel_length",
                                           "support_length", "unprinted_length")]
                + [(n, c_size_t) for n in ("support_corners", "corners_left_out", "neck_islands", "skin_bands",
                                           "band_retries", "corners_touched", "narrowed_islands")]
                + [("narrowed_volume", c_double), ("shift_retries", c_size_t)])


class amp_stroke_report(Structure):
    _fields_ = [("segments", c_size_t), ("pseudo", c_size_t), ("crossings", c_size_t),
                ("repeated_edges", c_size_t), ("outside", c_size_t), ("closed", c_int)]


class amp_gouge_violation(Structure):
    _fields_ = [("earlier_path", c_size_t), ("earlier_seg", c_size_t), ("later_path", c_size_t),
                ("later_seg", c_size_t), ("earlier_point", amp_vec3), ("later_point", amp_vec3),
                ("depth", c_double)]


class amp_field(Structure):
    _fields_ = [("eval", c_void_p), ("user", c_void_p), ("lo", c_double * 3), ("hi", c_double * 3),
                ("dir", c_int), ("p", c_double * 8)]


class amp_field_opts(Structure):
    _fields_ = [("spacing", c_double), ("pattern", c_int), ("step", c_double), ("min_len", c_double),
                ("radius", c_double), ("shells", c_int), ("within", c_void_p), ("without", c_void_p),
                ("nwithout", c_size_t), ("progress", PROGRESS_FN), ("progress_user", c_void_p)]


class amp_field_stats(Structure):
    _fields_ = [("curves", c_size_t), ("pieces", c_size_t), ("grid_a", c_size_t), ("grid_b", c_size_t),
                ("length_before", c_double), ("length_after", c_double), ("radius", c_double), ("target", c_double),
                ("bound", c_double), ("bound_met", c_int), ("inserted", c_size_t), ("route", c_int),
                ("shell_paths", c_size_t), ("shell_length", c_double), ("gap_curves", c_size_t),
                ("gap_left", c_size_t)]


AMP_SWEEP_MAX = 256


class amp_sweep(Structure):
    _fields_ = [("n", c_size_t), ("p", amp_vec3 * AMP_SWEEP_MAX), ("t", amp_vec3 * AMP_SWEEP_MAX),
                ("nrm", amp_vec3 * AMP_SWEEP_MAX), ("s", c_double * AMP_SWEEP_MAX)]


class amp_hold_opts(Structure):
    _fields_ = [(n, c_double) for n in ("overhang", "max_gap", "bridge", "cantilever", "step")]


class amp_hold_report(Structure):
    _fields_ = [("alloc", c_void_p), ("samples", c_size_t), ("unheld", c_size_t), ("bridges", c_size_t),
                ("bridged_mm", c_double), ("tips", c_size_t), ("failures", c_size_t), ("failed_mm", c_double),
                ("npaths_failed", c_size_t), ("paths_failed", POINTER(c_size_t)), ("worst_path", c_size_t),
                ("worst_mm", c_double), ("worst_at", amp_vec3)]


class amp_preview_stats(Structure):
    _fields_ = [("width", c_int), ("height", c_int), ("paths", c_size_t), ("support", c_size_t),
                ("vertices", c_size_t), ("drawn", c_size_t), ("bytes", c_size_t)]


class amp_preview_opts(Structure):
    _fields_ = [("width", c_int), ("progress", PROGRESS_FN), ("progress_user", c_void_p)]


_D = c_double
_GCODE_OPTS = [
    ("flavor", c_int), ("filament_diameter", _D), ("flow", _D), ("max_volumetric_flow", _D), ("print_feed", _D),
    ("travel_feed", _D), ("retract_length", _D), ("retract_speed", _D), ("z_hop", _D), ("travel_corridor", _D),
    ("end_lift", _D), ("relative_e", c_int), ("hotend_temp", _D), ("bed_temp", _D), ("start_gcode", c_char_p),
    ("end_gcode", c_char_p), ("accel", _D), ("junction_deviation", _D), ("max_feed_xy", _D), ("max_feed_z", _D),
    ("max_feed_e", _D), ("max_accel_xy", _D), ("max_accel_z", _D), ("max_accel_e", _D), ("retract_accel", _D),
    ("max_cross_section", _D), ("profile", c_char_p), ("place", c_int), ("place_x", _D), ("place_y", _D),
    ("bed_min_x", _D), ("bed_min_y", _D), ("bed_max_x", _D), ("bed_max_y", _D), ("max_height", _D),
    ("first_layer_height", _D), ("first_layer_feed", _D), ("first_layer_hotend_temp", _D),
    ("first_layer_bed_temp", _D), ("fan_off_layers", c_int), ("fan_speed", _D), ("retract_min_travel", _D),
    ("chord_tol", _D), ("radius_tol", _D), ("min_segment", _D), ("arcs", c_int),
    ("direct_hop", _D), ("head_z_offs", _D), ("head_theta", _D), ("bed_radius", _D)]


class amp_gcode_opts(Structure):
    _fields_ = _GCODE_OPTS


class amp_gcode_stats(Structure):
    _fields_ = ([(n, c_size_t) for n in ("lines", "paths", "paths_skipped", "segments", "travels", "retractions",
                                         "lowered_feed_segments")]
                + [(n, _D) for n in ("print_length", "travel_length", "filament_length", "filament_volume", "time",
                                     "print_time", "travel_time", "max_travel_z")]
                + [(n, c_size_t) for n in ("input_segments", "arcs", "travel_moves")]
                + [("bead_volume", _D), ("first_layer_z", _D), ("bbox", amp_box3), ("direct_hops", c_size_t),
                   ("first_layer_bbox", amp_box3), ("layers", c_size_t)])


class amp_printer(Structure):
    _fields_ = ([("name", c_char * AMP_PRINTER_NAME_MAX), ("model", c_char * AMP_PRINTER_NAME_MAX),
                 ("flavor", c_int)]
                + [(n, _D) for n in ("bed_min_x", "bed_min_y", "bed_max_x", "bed_max_y", "max_height",
                                     "nozzle_diameter", "filament_diameter", "layer_height", "first_layer_height",
                                     "temp", "first_layer_temp", "bed_temp", "first_layer_bed_temp",
                                     "fan_percent")]
                + [("fan_off_layers", c_int)]
                + [(n, _D) for n in ("retract_length", "retract_speed", "retract_lift", "retract_before_travel",
                                     "print_speed", "first_layer_speed", "travel_speed", "accel", "max_feed_xy",
                                     "max_feed_z", "max_feed_e", "max_accel_xy", "max_accel_z", "max_accel_e",
                                     "retract_accel", "max_volumetric_flow", "extrusion_multiplier")]
                + [("start_gcode", c_char * AMP_PRINTER_GCODE_MAX), ("end_gcode", c_char * AMP_PRINTER_GCODE_MAX),
                   ("unknown", c_char * AMP_PRINTER_UNKNOWN_MAX), ("n_unknown", c_size_t), ("n_keys", c_size_t),
                   ("start_out", c_char * AMP_PRINTER_GCODE_MAX), ("end_out", c_char * AMP_PRINTER_GCODE_MAX),
                   ("vars", c_char * AMP_PRINTER_VARS_MAX), ("vars_len", c_size_t), ("n_vars_dropped", c_size_t),
                   ("bed_radius", _D)])


# C name -> mirror, for python/tests/test_layout.py
STRUCTS = {cls.__name__: cls for cls in (
    amp_error, amp_vec3, amp_box3, amp_vec2, amp_pvert, amp_path, amp_pathset, amp_buf, amp_out, amp_spline,
    amp_tri, amp_mesh, amp_stl_stats, amp_head, amp_cover_opts, amp_cover_stats, amp_coverage, amp_order_opts,
    amp_order_stats, amp_mdr_opts, amp_mdr_stats, amp_support_opts, amp_support_stats, amp_ring, amp_polyset,
    amp_slice_opts, amp_layer, amp_slices, amp_contpath_opts, amp_contpath_stats, amp_stroke_report,
    amp_gouge_violation, amp_coverage_domain, amp_field, amp_field_opts, amp_field_stats, amp_sweep, amp_hold_opts,
    amp_hold_report, amp_preview_stats, amp_preview_opts, amp_gcode_opts, amp_gcode_stats,
    amp_printer)}

# ---------------------------------------------------------------- prototypes

P = POINTER
E = P(amp_error)
_PROTOS = {
    "amp_strerror": (c_char_p, [c_int]),
    "amp_error_clear": (None, [E]),
    "amp_pathset_init": (None, [P(amp_pathset), c_void_p]),
    "amp_pathset_free": (None, [P(amp_pathset)]),
    "amp_pathset_clear": (None, [P(amp_pathset)]),
    "amp_pathset_begin": (c_int, [P(amp_pathset), c_int, E]),
    "amp_pathset_push": (c_int, [P(amp_pathset), amp_vec3, c_double, E]),
    "amp_pathset_set_height": (c_int, [P(amp_pathset), c_double, E]),
    "amp_pathset_add": (c_int, [P(amp_pathset), c_int, P(amp_pvert), c_size_t, E]),
    "amp_pathset_append": (c_int, [P(amp_pathset), P(amp_pathset), E]),
    "amp_pathset_parse": (c_int, [P(amp_pathset), c_char_p, c_size_t, E]),
    "amp_pathset_read_file": (c_int, [P(amp_pathset), c_char_p, E]),
    "amp_pathset_read_file_progress": (c_int, [P(amp_pathset), c_char_p, PROGRESS_FN, c_void_p, E]),
    "amp_pathset_write": (c_int, [P(amp_pathset), c_char_p, c_void_p, c_void_p, E]),
    "amp_pathset_write_file": (c_int, [P(amp_pathset), c_char_p, c_char_p, E]),
    "amp_pathset_length": (c_double, [P(amp_pathset), c_int]),
    "amp_pathset_volume": (c_double, [P(amp_pathset), c_int]),
    "amp_pathset_bbox": (amp_box3, [P(amp_pathset)]),
    "amp_buf_init": (None, [P(amp_buf), c_void_p]),
    "amp_buf_free": (None, [P(amp_buf)]),
    "amp_out_open": (c_int, [P(amp_out), c_char_p, E]),
    "amp_out_commit": (c_int, [P(amp_out), E]),
    "amp_out_abort": (None, [P(amp_out)]),
    "amp_out_sink": (c_int, [P(amp_out), c_char_p, c_size_t]),
    "amp_spline_init": (None, [P(amp_spline)]),
    "amp_spline_free": (None, [P(amp_spline)]),
    "amp_spline_read_file": (c_int, [c_char_p, c_void_p, P(P(amp_spline)), P(c_size_t), E]),
    "amp_spline_parse": (c_int, [c_char_p, c_size_t, c_void_p, P(P(amp_spline)), P(c_size_t), E]),
    "amp_spline_list_free": (None, [c_void_p, P(amp_spline), c_size_t]),
    "amp_spline_write": (c_int, [P(amp_spline), c_int, c_void_p, c_void_p, E]),
    "amp_spline_eval": (c_int, [P(amp_spline), P(c_double), P(amp_vec3), E]),
    "amp_spline_cp_bbox": (amp_box3, [P(amp_spline)]),
    "amp_trivariate_model": (c_int, [c_char_p, c_void_p, P(amp_spline), E]),
    "amp_trivariate_model_names": (P(c_char_p), []),
    "amp_trivariate_volume": (c_double, [P(amp_spline)]),
    "amp_mesh_init": (None, [P(amp_mesh), c_void_p]),
    "amp_mesh_free": (None, [P(amp_mesh)]),
    "amp_mesh_bbox": (amp_box3, [P(amp_mesh)]),
    "amp_mesh_volume": (c_double, [P(amp_mesh)]),
    "amp_mesh_orient": (c_int, [P(amp_mesh), P(c_size_t), E]),
    "amp_mesh_read_stl_ex": (c_int, [P(amp_mesh), c_char_p, c_size_t, P(amp_stl_stats), E]),
    "amp_mesh_read_stl_file_ex": (c_int, [P(amp_mesh), c_char_p, P(amp_stl_stats), E]),
    "amp_mesh_write_stl": (c_int, [P(amp_mesh), c_int, c_void_p, c_void_p, E]),
    "amp_mesh_write_stl_file": (c_int, [P(amp_mesh), c_char_p, c_int, E]),
    "amp_mesh_model": (c_int, [c_char_p, c_double, P(amp_mesh), E]),
    "amp_mesh_model_count": (c_size_t, []),
    "amp_mesh_model_name": (c_char_p, [c_size_t]),
    "amp_mesh_from_trivariate": (c_int, [P(amp_mesh), P(amp_spline), c_int, E]),
    "amp_bvh_build": (c_int, [P(c_void_p), P(amp_mesh), E]),
    "amp_bvh_free": (None, [c_void_p]),
    "amp_cover_opts_default": (None, [P(amp_cover_opts)]),
    "amp_cover_trivariate": (c_int, [P(amp_spline), P(amp_cover_opts), P(amp_pathset), P(amp_cover_stats), E]),
    "amp_cover_estimate": (c_int, [P(amp_spline), P(amp_cover_opts), P(c_double), P(c_double), E]),
    "amp_check_coverage": (c_int, [P(amp_pathset), P(amp_coverage_domain), c_size_t, c_ulong, P(amp_coverage), E]),
    "amp_head_default": (None, [P(amp_head)]),
    "amp_head_validate": (c_int, [P(amp_head), E]),
    "amp_order_opts_default": (None, [P(amp_order_opts)]),
    "amp_order": (c_int, [P(amp_pathset), P(amp_order_opts), P(amp_pathset), P(amp_order_stats), E]),
    "amp_mdr_opts_default": (None, [P(amp_mdr_opts), c_double]),
    "amp_mdr": (c_int, [P(amp_pathset), P(amp_mdr_opts), P(amp_pathset), P(amp_mdr_stats), E]),
    "amp_tubes_union_volume": (c_int, [P(amp_pathset), c_size_t, P(c_double), E]),
    "amp_support_opts_default": (None, [P(amp_support_opts)]),
    "amp_support": (c_int, [P(amp_pathset), c_void_p, P(amp_support_opts), P(amp_pathset), P(amp_support_stats),
                            E]),
    "amp_field_builtin": (c_int, [P(amp_field), c_char_p, amp_box3, E]),
    "amp_field_from_spline": (c_int, [P(amp_field), P(amp_spline), c_int, E]),
    "amp_field_sweep": (c_int, [P(amp_field), P(amp_sweep), P(amp_vec3), c_size_t, c_double, E]),
    "amp_field_opts_default": (None, [P(amp_field_opts)]),
    "amp_field_cover": (c_int, [P(amp_field), c_void_p, P(amp_field_opts), P(amp_pathset), P(amp_field_stats), E]),
    "amp_over_coverage": (c_double, [P(amp_pathset), c_double]),
    "amp_bvh_inside": (c_int, [c_void_p, amp_vec3]),
    "amp_bvh_closest": (c_double, [c_void_p, amp_vec3, P(amp_vec3), P(c_size_t)]),
    "amp_hold_opts_default": (None, [P(amp_hold_opts)]),
    "amp_check_hold": (c_int, [P(amp_pathset), P(amp_hold_opts), P(amp_hold_report), E]),
    "amp_hold_report_free": (None, [P(amp_hold_report)]),
    "amp_slices_init": (None, [P(amp_slices), c_void_p]),
    "amp_slices_free": (None, [P(amp_slices)]),
    "amp_slice_mesh": (c_int, [P(amp_mesh), P(amp_slice_opts), P(amp_slices), E]),
    "amp_polyset_area": (c_double, [P(amp_polyset)]),
    "amp_slices_overhang": (c_double, [P(amp_slices), c_size_t, c_double]),
    "amp_contpath_opts_default": (None, [P(amp_contpath_opts), c_double]),
    "amp_contpath_layers": (c_int, [P(amp_slices), P(amp_contpath_opts), P(amp_pathset), P(amp_contpath_stats),
                                    E]),
    "amp_check_hold_runs": (c_int, [P(amp_pathset), c_double, c_void_p, c_void_p, E]),
    "amp_check_path_stroke": (c_int, [P(amp_pathset), c_size_t, P(amp_polyset), c_double, P(amp_stroke_report),
                                      E]),
    "amp_check_gouge": (c_int, [P(amp_pathset), P(amp_head), c_int, c_double, P(amp_gouge_violation), E]),
    "amp_preview_png": (c_int, [P(amp_pathset), c_int, c_void_p, c_void_p, P(amp_preview_stats), E]),
    "amp_preview_svg": (c_int, [P(amp_pathset), c_int, c_void_p, c_void_p, P(amp_preview_stats), E]),
    "amp_preview_png_opts": (c_int, [P(amp_pathset), P(amp_preview_opts), c_void_p, c_void_p, P(amp_preview_stats),
                                     E]),
    "amp_preview_svg_opts": (c_int, [P(amp_pathset), P(amp_preview_opts), c_void_p, c_void_p, P(amp_preview_stats),
                                     E]),
    "amp_printer_builtin_count": (c_size_t, []),
    "amp_printer_builtin_name": (c_char_p, [c_size_t]),
    "amp_printer_builtin_about": (c_char_p, [c_size_t]),
    "amp_printer_load": (c_int, [P(amp_printer), c_char_p, E]),
    "amp_printer_check": (c_int, [P(amp_printer), E]),
    "amp_printer_gcode_opts": (c_int, [P(amp_printer), P(amp_gcode_opts), E]),
    "amp_printer_gcode_job": (c_int, [P(amp_printer), P(amp_gcode_opts), P(amp_pathset), c_void_p, E]),
    "amp_printer_bead_width": (c_double, [P(amp_printer)]),
    "amp_gcode_opts_default": (None, [P(amp_gcode_opts), c_int]),
    "amp_gcode_junction_default": (c_double, [c_int, c_double]),
    "amp_gcode_write": (c_int, [P(amp_pathset), P(amp_gcode_opts), c_void_p, c_void_p, P(amp_gcode_stats), E]),
}

# newer than some installed libraries: their absence makes only the feature unavailable
OPTIONAL = {"amp_preview_png", "amp_preview_svg", "amp_preview_png_opts", "amp_preview_svg_opts",
            "amp_pathset_read_file_progress"}
MISSING = set()
for _name, (_res, _args) in _PROTOS.items():
    try:
        _f = getattr(lib, _name)
    except AttributeError:
        if _name not in OPTIONAL:
            raise ImportError("%s lacks %s: a libampath older than this package?" % (LIBRARY_PATH, _name))
        MISSING.add(_name)
        continue
    _f.restype = _res
    _f.argtypes = _args

# sinks of the library itself, passed as plain function pointers (no Python call per write)
BUF_SINK = ctypes.cast(lib.amp_buf_sink, c_void_p)
OUT_SINK = ctypes.cast(lib.amp_out_sink, c_void_p)

# ---------------------------------------------------------------- guarding against a stale mirror
#
# A mirror smaller than the C struct lets the library write past the Python object: heap corruption, a
# segfault later. Structs the library writes into are therefore allocated with GUARD spare bytes holding a
# pattern (new()); intact() says whether a call wrote into them. And at import, every *_opts_default
# function fills an oversized buffer: a write past the mirror's size means a stale _lib.py, refused with
# ImportError before any call (python/tests/test_layout.py names the field; run.py runs it first).

GUARD = 256
_PATTERN = 0xA5


class StaleMirror(ImportError):
    """The loaded libampath's structs are larger than the ctypes mirrors of this package."""


def new(cls):
    """An instance of mirror @cls followed by GUARD pattern bytes (kept alive with it)."""
    n = ctypes.sizeof(cls)
    buf = (c_char * (n + GUARD)).from_buffer(bytearray(b"\0" * n + bytes([_PATTERN]) * GUARD))
    obj = cls.from_buffer(buf)
    obj._guard = buf
    return obj


def intact(obj):
    """False when a library call wrote past the mirror @obj (made by new())."""
    buf = getattr(obj, "_guard", None)
    if buf is None:
        return True
    n = ctypes.sizeof(type(obj))
    return all(b == _PATTERN for b in bytes(buf)[n:])


def stale(cls, fn):
    return StaleMirror("%s: %s wrote past the %d bytes of the ctypes mirror of %s: python/ampath/_lib.py does "
                       "not match this library's headers (python/tests/test_layout.py names the fields to fix)"
                       % (LIBRARY_PATH, fn, ctypes.sizeof(cls), cls.__name__))


DEFAULTS = ((amp_cover_opts, "amp_cover_opts_default", ()), (amp_order_opts, "amp_order_opts_default", ()),
            (amp_mdr_opts, "amp_mdr_opts_default", (0.5,)), (amp_support_opts, "amp_support_opts_default", ()),
            (amp_field_opts, "amp_field_opts_default", ()),
            (amp_contpath_opts, "amp_contpath_opts_default", (0.225,)),
            (amp_gcode_opts, "amp_gcode_opts_default", (0,)), (amp_hold_opts, "amp_hold_opts_default", ()))


def probe_default(cls, fn, args=(), c_struct=None):
    """Call @fn (an *_opts_default) on a guarded @cls; StaleMirror if it writes past @cls. @c_struct: the
    mirror its prototype takes (default @cls; a test passes an outdated @cls)."""
    o = new(cls)
    getattr(lib, fn)(ctypes.cast(ctypes.pointer(o), POINTER(c_struct or cls)), *args)
    if not intact(o):
        raise stale(cls, fn)


for _cls, _fn, _args in DEFAULTS:
    probe_default(_cls, _fn, _args)
