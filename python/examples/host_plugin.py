#!/usr/bin/env python3
"""What a printer-host plugin (OctoPrint, Moonraker, Printrun) would run when a user uploads an STL:
slice it into continuous tool paths (paper 2: one stroke per island per layer) for the chosen printer
profile, verify the strokes, write print-ready G-code next to the upload, and hand it to ampath-bridge's
daemon (or just keep the file).

    python3 host_plugin.py part.stl --printer prusa-mk3s                 # part.gcode next to part.stl
    python3 host_plugin.py part.stl --printer my.ini --bridge SOCKET     # ... and print it, following events

One JSON object on stdout says what was done (for the host's log); progress and events go to stderr.
Exit status: 0 done, 1 the print or a check failed, 2 bad input (the library's message on stderr).
"""

import argparse
import json
import os
import sys

try:
    import ampath
except ImportError:  # run from the source tree without installing
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    import ampath


def make_gcode(stl, printer, layer=None, place=None):
    """The print-ready job for @stl on @printer: (G-code path, figures)."""
    pr = ampath.Printer(printer)
    layer = layer or pr.layer_height
    with ampath.Mesh.load(stl) as mesh:
        # beads 1.125 x the profile's nozzle wide (docs/interfaces.md §4, as `ampath slice --continuous --printer`);
        # every stroke is checked against its layer there (an Error when one fails)
        with ampath.Slices(mesh, layer, pr.first_layer_height) as sl:
            paths = sl.continuous(printer=pr)
    with paths:
        report = ampath.check(paths)
        if not report["ok"]:
            raise SystemExit("ampath check failed on the strokes: %s" % json.dumps(report["strokes"]))
        out = os.path.splitext(stl)[0] + ".gcode"
        job = ampath.gcode(paths, out, printer=pr, place=place)
    return out, {"printer": pr.name, "layers": paths.stats["layers"], "strokes": paths.stats["strokes"],
                 "lines": job.stats["lines"], "time_s": round(job.stats["time"], 1),
                 "filament_mm": round(job.stats["filament_length"], 1), "bbox": job.stats["bbox"]}


def send(socket_path, gcode, follow):
    """Submit @gcode to the daemon; with @follow, wait for the end of the job and return its state."""
    with ampath.BridgeClient(socket_path) as bridge:
        if follow:
            bridge.subscribe()
        reply = bridge.submit(gcode)
        print("bridge:", reply.get("message", "started"), file=sys.stderr)
        if not follow:
            return "submitted"
        for ev in bridge.events():
            if ev["event"] == "progress":
                print("printing: %d/%d (%.0f %%)" % (ev["acked"], ev["total"], ev["percent"]), file=sys.stderr)
            elif ev["event"] == "error":
                print("printer:", ev.get("text"), file=sys.stderr)
            elif ev["event"] == "end":
                return ev["state"]
        return "connection closed"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("stl", help="the uploaded STL")
    ap.add_argument("--printer", default="generic", help="built-in profile or slicer .ini (default generic)")
    ap.add_argument("--layer", type=float, help="layer height, mm (default: the profile's)")
    ap.add_argument("--place", help="X,Y: centre of the part on the bed (default: the bed's centre)")
    ap.add_argument("--bridge", metavar="SOCKET", nargs="?", const="",
                    help="submit to ampath-bridge --daemon (its default socket when no SOCKET is given)")
    ap.add_argument("--follow", action="store_true", help="with --bridge: follow the job to its end")
    a = ap.parse_args(argv)
    place = tuple(float(c) for c in a.place.split(",")) if a.place else None
    try:
        gcode, figures = make_gcode(a.stl, a.printer, a.layer, place)
        figures["gcode"] = gcode
        if a.bridge is not None:
            figures["bridge"] = send(a.bridge or None, gcode, a.follow)
    except ampath.BridgeError as e:  # an ampath.Error too: caught first
        print("host_plugin: bridge: %s" % e.message, file=sys.stderr)
        return 1
    except ampath.Error as e:
        print("host_plugin: %s" % e.message, file=sys.stderr)
        return 2
    print(json.dumps(figures))
    return 0 if figures.get("bridge", "done") in ("done", "submitted") else 1


if __name__ == "__main__":
    sys.exit(main())
