"""A client of ampath-bridge's JSON control socket (docs/bridge.md): one JSON object per line each way;
replies carry "ok" (and echo our "id"), events carry "event".

    with ampath.BridgeClient() as b:          # the daemon's default socket
        b.subscribe()
        b.submit("/abs/path/job.gcode")
        for ev in b.events():
            if ev["event"] == "end":
                break

Pure standard library (no libampath call; failures are ampath.Error all the same). Thread-safe: requests
from any thread, events() in one consumer thread at the same time (a reader thread sorts the lines).
"""

import collections
import json
import os
import socket
import threading

from .core import Error

_ERR_IO, _ERR_STATE = -5, -8  # AMP_ERR_IO, AMP_ERR_STATE


class BridgeError(Error):
    """The daemon refused a request (status AMP_ERR_STATE; .reply holds its answer) or the connection failed
    (AMP_ERR_IO). A subclass of ampath.Error: `except ampath.Error` catches the bridge's failures too."""

    def __init__(self, message, reply=None, status=_ERR_IO):
        super().__init__(status, message)
        self.reply = reply


def default_socket():
    """Where the daemon puts its socket without --socket (docs/bridge.md "Where the socket lives")."""
    run = os.environ.get("XDG_RUNTIME_DIR")
    if run:
        return os.path.join(run, "ampath-bridge.sock")
    return os.path.join(os.environ.get("TMPDIR") or "/tmp", "ampath-bridge-%d" % os.getuid(), "ctl.sock")


class BridgeClient:
    """One connection to the daemon. Thread-safe: any thread may send requests while another iterates over
    events(); a reader thread of the client sorts what arrives into replies (by "id") and events."""

    def __init__(self, path=None, timeout=30.0):
        self.path = path or default_socket()
        self.timeout = timeout
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            self._sock.settimeout(timeout)
            self._sock.connect(self.path)
            self._sock.settimeout(None)  # the reader blocks; waits are bounded on the conditions below
        except OSError as e:
            self._sock.close()
            raise BridgeError("%s: %s" % (self.path, e.strerror or e)) from e
        self._send_lock = threading.Lock()
        self._cond = threading.Condition()
        self._replies = {}  # id -> reply, until its request takes it
        self._pending = []  # ids sent and not answered, oldest first
        self._events = collections.deque()
        self._eof = None  # why the connection ended (str), once it has
        self._next_id = 1
        self._reader = threading.Thread(target=self._read_loop, name="ampath-bridge-reader", daemon=True)
        self._reader.start()

    # ------------------------------------------------------------ plumbing

    def close(self):
        """Close the connection (idempotent); the reader thread ends."""
        sock, self._sock = getattr(self, "_sock", None), None
        if sock is None:
            return
        try:
            sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        sock.close()
        reader = getattr(self, "_reader", None)
        if reader is not None and reader is not threading.current_thread():
            reader.join()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _read_loop(self):
        buf, sock, why = b"", self._sock, "the daemon closed the connection"
        try:
            while True:
                chunk = sock.recv(65536)
                if not chunk:
                    break
                buf += chunk
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    if line.strip():
                        self._deliver(json.loads(line.decode("utf-8")))
        except (OSError, ValueError) as e:
            why = "connection lost: %s" % e if self._sock is not None else "closed"
        with self._cond:
            self._eof = why if self._sock is not None else "closed"
            self._cond.notify_all()

    def _deliver(self, msg):
        with self._cond:
            if "event" in msg:
                self._events.append(msg)
            else:
                rid = msg.get("id")
                if rid not in self._pending and self._pending:
                    rid = self._pending[0]  # a reply without our id answers the oldest request
                if rid in self._pending:
                    self._pending.remove(rid)
                    self._replies[rid] = msg
            self._cond.notify_all()

    def request(self, cmd, **fields):
        """Send one request and return its reply (a dict). Raises BridgeError when the reply says
        "ok": false (AMP_ERR_STATE), or when no reply comes within the client's timeout (AMP_ERR_IO)."""
        with self._cond:
            if self._sock is None or self._eof:
                raise BridgeError("%s: %s" % (cmd, self._eof or "closed"))
            rid = self._next_id
            self._next_id += 1
            self._pending.append(rid)
        try:
            with self._send_lock:
                self._sock.sendall((json.dumps(dict(fields, cmd=cmd, id=rid)) + "\n").encode())
        except (OSError, AttributeError) as e:
            raise BridgeError("%s: %s" % (cmd, getattr(e, "strerror", None) or e)) from e
        with self._cond:
            if not self._cond.wait_for(lambda: rid in self._replies or self._eof, self.timeout):
                self._pending.remove(rid)  # a late reply is dropped
                raise BridgeError("no reply to %s within %g s" % (cmd, self.timeout))
            reply = self._replies.pop(rid, None)
        if reply is None:
            raise BridgeError("%s: %s" % (cmd, self._eof))
        if not reply.get("ok"):
            raise BridgeError("%s: %s" % (cmd, reply.get("error", "refused")), reply, _ERR_STATE)
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
        Ends when the connection ends, or when no event came for @timeout seconds (None: no limit).
        Meant for one consumer; other threads may send requests meanwhile."""
        while True:
            with self._cond:
                if not self._cond.wait_for(lambda: self._events or self._eof, timeout):
                    return
                if not self._events:
                    return
                ev = self._events.popleft()
            yield ev
