"""ampath.BridgeClient against the real daemon (bridge/ampath-bridge --daemon) and the virtual printer
(tools/ampath-vprinter), started as tests/test_daemon.c starts them. The job is G-code made by Python."""

import json
import os
import signal
import subprocess
import sys
import threading
import time
import unittest

from amptest import BRIDGE, HERE, VPRINTER, TmpCase, ampath

EXAMPLE = os.path.join(HERE, "..", "examples", "host_plugin.py")
README = os.path.join(HERE, "..", "..", "README.md")


def readme_python():
    """The Python example of README.md's section "Using ampath from Python"."""
    with open(README) as f:
        text = f.read()
    section = text[text.index("## Using ampath from Python"):]
    start = section.index("```python\n") + len("```python\n")
    return section[start:section.index("```\n", start)]


def box_stl(path, sx=12.0, sy=8.0, sz=1.2, at=(0, 0, 0)):
    """An ASCII STL of a closed box (two outward triangles per face), on the plate or with its lowest
    corner @at."""
    v = [(at[0] + x * sx, at[1] + y * sy, at[2] + z * sz) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    with open(path, "w") as f:
        f.write("solid box\n")
        for a, b, c, d in quads:
            for tri in ((a, b, c), (a, c, d)):
                f.write("facet normal 0 0 0\nouter loop\n")
                for k in tri:
                    f.write("vertex %g %g %g\n" % v[k])
                f.write("endloop\nendfacet\n")
        f.write("endsolid box\n")

FAST = ["--timeout", "0.3", "--settle-ms", "5", "--boot-wait", "0.3", "--baud", "1000000"]
DEADLINE = 120.0  # generous: the machine may be loaded; nothing here measures time


def wait_for(cond, what):
    t0 = time.monotonic()
    while time.monotonic() - t0 < DEADLINE:
        v = cond()
        if v:
            return v
        time.sleep(0.02)
    raise AssertionError("timed out waiting for " + what)


@unittest.skipUnless(os.access(BRIDGE, os.X_OK) and os.access(VPRINTER, os.X_OK), "bridge not built")
class Bridge(TmpCase):
    def setUp(self):
        super().setUp()
        self.link, self.log, self.sock = self.p("printer"), self.p("printer.log"), self.p("ctl.sock")
        self.vp = subprocess.Popen([VPRINTER, "--link", self.link, "--log", self.log] + self.vp_opts(),
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wait_for(lambda: os.path.exists(self.link), "the virtual printer's link")
        self.err = open(self.p("daemon.err"), "w+")
        self.daemon = subprocess.Popen([BRIDGE, self.link, "--daemon", "--socket", self.sock] + FAST,
                                       stdout=subprocess.DEVNULL, stderr=self.err)
        # up when it says so on stderr (as tests/test_daemon.c waits)
        wait_for(lambda: self.daemon.poll() is not None or "control socket " in self.daemon_err(), "the daemon")
        self.assertIsNone(self.daemon.poll(), self.daemon_err())

    def vp_opts(self):
        # the pause/cancel job takes the virtual printer about 30 s of modelled motion (2 mm moves at 20 mm/s):
        # it cannot end between our submit and our pause however slow this machine is, and a cancel
        # waits only for the few lines in flight
        return ["--speed", "20"] if "pause" in self._testMethodName else []

    def daemon_err(self):
        self.err.seek(0)
        return self.err.read()

    def tearDown(self):
        for proc in (self.daemon, self.vp):
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(timeout=DEADLINE)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
        self.err.close()
        super().tearDown()

    def job(self, n=40, length=20):
        with ampath.PathSet() as ps:
            for k in range(n):
                y, z = 3 * k % 30, 0.2 + 0.2 * (k // 10)
                ps.add([(0, y, z), (length, y, z)], radius=0.25, h=0.2)
            path = self.p("job.gcode")
            ampath.gcode(ps, path, hotend_temp=0, bed_temp=0, first_layer_hotend_temp=0, first_layer_bed_temp=0)
        return path

    def executed(self):
        with open(self.log) as f:
            # the handshake (M110, M115, M105) and the closing M105 that recovers lost oks are the bridge's own
            return [l for l in f if not l.startswith("#") and "M110" not in l and "M115" not in l and "M105" not in l]

    def follow(self, b):
        for ev in b.events(timeout=DEADLINE):
            if ev["event"] == "end":
                return ev
        self.fail("no end event")

    def test_submit_and_follow_a_job_to_its_end(self):
        job = self.job()
        with ampath.BridgeClient(self.sock) as b:
            self.assertEqual(b.status()["state"], "idle")
            b.subscribe()
            reply = b.submit(job)
            self.assertTrue(reply["ok"])
            kinds = set()
            for ev in b.events(timeout=DEADLINE):
                kinds.add(ev["event"])
                if ev["event"] == "end":
                    end = ev
                    break
            self.assertEqual(end["state"], "done")
            self.assertIn("state", kinds)
            st = b.status()
            self.assertEqual(st["acked"], st["total"])
            self.assertEqual(st["errors"], 0)
        self.assertEqual(len(self.executed()), st["total"])

    def test_the_example_host_plugin_slices_an_upload_and_prints_it(self):
        stl = self.p("upload.stl")
        box_stl(stl)
        r = subprocess.run([sys.executable, EXAMPLE, stl, "--printer", "ender3", "--bridge", self.sock, "--follow"],
                           capture_output=True, text=True, timeout=DEADLINE)
        self.assertEqual(r.returncode, 0, r.stderr)
        figures = json.loads(r.stdout)
        self.assertEqual(figures["bridge"], "done")
        self.assertEqual(figures["printer"], "ender3")
        self.assertEqual(figures["gcode"], self.p("upload.gcode"))
        self.assertGreater(figures["strokes"], 0)
        with open(figures["gcode"]) as f:
            moves = sum(1 for l in f if l.startswith(("G0 ", "G1 ")))
        done = sum(1 for l in self.executed() if " G0 " in l or " G1 " in l)
        self.assertEqual(done, moves)

    def test_the_readme_example_runs_as_written(self):
        """README.md "Using ampath from Python", run as a user would: in a directory holding part.stl (and
        the spine and region it names), with the daemon at its default socket ($XDG_RUNTIME_DIR)."""
        work = self.p("user")
        os.makedirs(work)
        box_stl(os.path.join(work, "part.stl"), 20, 10, 6)
        with open(os.path.join(work, "spine.amp"), "w") as f:
            f.write("ampath-paths 1\npath object 2\n5 5 -1 1\n5 5 7 1\n")  # a square of side 4 along it
        box_stl(os.path.join(work, "region.stl"), 3, 3, 8, at=(3.5, 3.5, -1))  # inside the sweep
        # the daemon's default socket in a runtime directory of ours (mode 0700, as logind makes it)
        run = self.p("run")
        os.makedirs(run, mode=0o700)
        os.symlink(self.sock, os.path.join(run, "ampath-bridge.sock"))
        env = dict(os.environ, XDG_RUNTIME_DIR=run, PYTHONPATH=os.path.join(HERE, ".."))
        r = subprocess.run([sys.executable, "-c", readme_python()], cwd=work, env=env, capture_output=True, text=True,
                           timeout=1800)
        self.assertEqual(r.returncode, 0, r.stderr[-3000:])
        out = r.stdout.splitlines()
        self.assertEqual(out[-1], "done")  # the job printed on the virtual printer
        self.assertIn("AMP_ERR_IO", out[-2])
        self.assertTrue(all(os.path.exists(os.path.join(work, f)) for f in ("helix.gcode", "mine.gcode")))
        import ast
        figures = [ast.literal_eval(l) for l in out if l.startswith("{")]
        strokes, cover = [d for d in figures if "ran" in d]
        self.assertTrue(strokes["ok"] and strokes["paths"] > 0, strokes)
        self.assertTrue(cover["ok"] and cover["model"] == "mesh", cover)  # the two fields cover the part

    def test_refusals_raise_bridge_error_with_the_reply(self):
        with ampath.BridgeClient(self.sock) as b:
            with self.assertRaises(ampath.BridgeError) as cm:
                b.submit(self.p("no-such-job.gcode"))
            self.assertFalse(cm.exception.reply["ok"])
            self.assertIsInstance(cm.exception, ampath.Error)  # one exception type for the whole package
            self.assertEqual(cm.exception.name, "AMP_ERR_STATE")
            self.assertIn("no-such-job", str(cm.exception))
            self.assertEqual(b.status()["state"], "idle")  # the connection still works
        with self.assertRaises(ampath.BridgeError) as cm:
            ampath.BridgeClient(self.p("no-such.sock"))
        self.assertEqual(cm.exception.name, "AMP_ERR_IO")

    def test_pause_resume_and_cancel_while_another_thread_follows_the_events(self):
        """A host follows the events in one thread while its UI pauses, resumes and cancels from another:
        no request waits for the next event (while paused there is none)."""
        job = self.job(150, length=2)
        seen, done = [], threading.Event()

        def consume(b):
            for ev in b.events(timeout=DEADLINE):
                seen.append(ev)
                if ev["event"] == "end":
                    break
            done.set()

        with ampath.BridgeClient(self.sock) as b:
            b.subscribe()
            b.submit(job)
            consumer = threading.Thread(target=consume, args=(b,))
            consumer.start()
            b.pause()
            wait_for(lambda: b.status()["state"] == "paused", "paused")
            wait_for(lambda: any(e["event"] == "state" and e["state"] == "paused" for e in seen), "the paused event")
            b.resume()  # the consumer waits for an event meanwhile: before, this waited for it to time out
            self.assertFalse(done.is_set(), "resume() waited for the event consumer")
            wait_for(lambda: b.status()["state"] != "paused", "resumed")
            b.cancel()
            consumer.join(DEADLINE)
            end = seen[-1]
            self.assertEqual(end["event"], "end")
            self.assertEqual(end["state"], "cancelled")
            self.assertLess(end["acked"], end["total"])
        self.assertRaises(ampath.BridgeError, b.status)  # closed

    def test_a_closed_connection_ends_the_events_and_fails_requests(self):
        with ampath.BridgeClient(self.sock) as b, ampath.BridgeClient(self.sock) as other:
            b.subscribe()
            other.quit()  # the daemon exits: our connection ends
            self.assertEqual([e for e in b.events(timeout=DEADLINE) if e["event"] == "end"], [])
            with self.assertRaises(ampath.Error) as cm:
                b.status()
            self.assertEqual(cm.exception.name, "AMP_ERR_IO")
        self.assertEqual(self.daemon.wait(DEADLINE), 0)


if __name__ == "__main__":
    unittest.main()
