"""A client of ampath-bridge's JSON control socket (docs/bridge.md): one JSON object per line each way;
replies carry "ok" (and echo our "id"), events carry "event".

    with ampath.BridgeClient() as b:          # the daemon's default socket
        b.subscribe()
        b.submit("/abs/path/job.gcode")
        for ev in b.events():
            if ev["event"] == "end":
                break

Pure standard library; no libampath call. Requests from several threads are serialised by a lock;
events() is meant for one consumer.
"""

import collections
import json
import os
import socket
import threading


class BridgeError(Exception):
    """The daemon refused a request (.reply holds its answer) or the connection failed."""

    def __init__(self, message, reply=None):
        super().__init__(message)
        self.reply = reply


def default_socket():
    """Where the daemon puts its socket without --socket (docs/bridge.md "Where the socket lives")."""
    run = os.environ.get("XDG_RUNTIME_DIR")
    if run:
        return os.path.join(run, "ampath-bridge.sock")
    return os.path.join(os.environ.get("TMPDIR") or "/tmp", "ampath-bridge-%d" % os.getuid(), "ctl.sock")


class BridgeClient:
    def __init__(self, path=None, timeout=30.0):
        self.path = path or default_socket()
        self.timeout = timeout
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._sock.settimeout(timeout)
        try:
            self._sock.connect(self.path)
        except OSError as e:
            self._sock.close()
            raise BridgeError("%s: %s" % (self.path, e.strerror or e)) from e
        self._buf = b""
        self._events = collections.deque()
        self._lock = threading.Lock()
        self._next_id = 1

    # ------------------------------------------------------------ plumbing

    def close(self):
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _readline(self, timeout):
        while b"\n" not in self._buf:
            self._sock.settimeout(timeout)
            try:
                chunk = self._sock.recv(65536)
            except socket.timeout:
                return None
            if not chunk:
                raise EOFError("the daemon closed the connection")
            self._buf += chunk
        line, self._buf = self._buf.split(b"\n", 1)
        return json.loads(line.decode("utf-8"))

    def request(self, cmd, **fields):
        """Send one request and return its reply (a dict); events that arrive first are kept for events().
        Raises BridgeError when the reply says "ok": false."""
        with self._lock:
            if self._sock is None:
                raise BridgeError("closed")
            rid = self._next_id
            self._next_id += 1
            msg = dict(fields, cmd=cmd, id=rid)
            self._sock.sendall((json.dumps(msg) + "\n").encode())
            while True:
                try:
                    reply = self._readline(self.timeout)
                except EOFError as e:
                    raise BridgeError(str(e)) from e
                if reply is None:
                    raise BridgeError("no reply to %s within %g s" % (cmd, self.timeout))
                if "event" in reply:
                    self._events.append(reply)
                    continue
                if reply.get("id", rid) != rid:
                    continue
                if not reply.get("ok"):
                    raise BridgeError("%s: %s" % (cmd, reply.get("error", "refused")), reply)
                return reply

    # ------------------------------------------------------------ the commands of docs/bridge.md

    def submit(self, path, from_line=None):
        """Start a job (.gcode or .amp); the path is made absolute (the daemon requires it)."""
        fields = {"path": os.path.abspath(path)}
        if from_line is not None:
            fields["from"] = int(from_line)
        return self.request("submit", **fields)

    def status(self):
        return self.request("status")

    def pause(self):
        return self.request("pause")

    def resume(self):
        return self.request("resume")

    def cancel(self):
        return self.request("cancel")

    def estop(self):
        return self.request("estop")

    def subscribe(self):
        return self.request("subscribe")

    def unsubscribe(self):
        return self.request("unsubscribe")

    def quit(self):
        return self.request("quit")

    def events(self, timeout=None):
        """Iterate over events ({"event": "state"|"progress"|"error"|"warning"|"end", ...}) after subscribe().
        Ends when the daemon closes the connection, or when no event came for @timeout seconds."""
        while True:
            with self._lock:
                if self._events:
                    ev = self._events.popleft()
                else:
                    if self._sock is None:
                        return
                    try:
                        ev = self._readline(timeout)
                    except EOFError:
                        return
                    if ev is None:
                        return
                    if "event" not in ev:
                        continue  # a late reply to a request that timed out
            yield ev
