#!/usr/bin/env python3
"""Client of the rowloc localization service (`rowloc serve`, docs/service.md).

Standard library only (Python 3.9+): copy this one file next to your program. The protocol is
newline-delimited JSON over TCP or a Unix socket; this module frames it, matches replies to
requests by `id`, keeps the lines the server pushes (subscriptions, errors of un-acknowledged
sensor messages) in a queue, and turns `error` replies into `RowlocError`.

Example (a server started with
`rowloc serve --port 7878 --vehicles config/vehicles --maps maps --filters config/filters`)::

    from rowloc_client import RowlocClient, read_log_header, stream_log

    log = "run/v4/sensors.ndjson"          # a sensor log (docs/protocol.md §1), e.g. `rowloc simulate`
    with RowlocClient.connect("127.0.0.1", 7878) as client:
        print(client.hello()["server"])
        client.open_session("vineyard-ugv-4ws", map="sample-vineyard",
                            header=read_log_header(log), session="ugv1")
        stream_log(client, "ugv1", log, rate="max")
        state = client.get_state("ugv1")
        if state["initialised"]:
            print(state["t"], state["x_m"], state["y_m"], state["phi_rad"])
        client.close_session("ugv1")

Smoke test: `python3 rowloc_client.py 127.0.0.1:7878` prints the server's hello and its sessions.

A client is not thread-safe: use one per thread (sessions are not tied to connections, so several
connections may feed and read the same session).
"""

from __future__ import annotations

import collections
import json
import math
import os
import select
import socket
import sys
import time

__all__ = [
    "PROTOCOL",
    "Message",
    "RowlocError",
    "ProtocolError",
    "RowlocClient",
    "read_log_header",
    "read_log",
    "stream_log",
    "add_session_key",
    "parse_address",
]

PROTOCOL = "rowloc-service/1"
DEFAULT_PORT = 7878
SENSOR_TYPES = frozenset(("gps", "imu", "wheels", "steering", "ultrasonic", "vio"))


class Message(dict):
    """One line received from the server: the parsed JSON object, plus `.raw`, its exact text
    (without the newline)."""

    __slots__ = ("raw",)

    def __init__(self, value, raw: str):
        super().__init__(value)
        self.raw = raw


class RowlocError(Exception):
    """An `error` reply of the server (docs/service.md §7): `.code` (e.g. "unknown_session"),
    `.message` (the server's text), `.reply` (the whole error line, a dict, or None)."""

    def __init__(self, code: str, message: str = "", reply: dict | None = None):
        super().__init__(f"{code}: {message}" if message else code)
        self.code = code
        self.message = message
        self.reply = reply

    @property
    def line(self):
        """The line number on the connection that the server named, or None."""
        return None if self.reply is None else self.reply.get("line")


class ProtocolError(RowlocError):
    """The server sent something this client cannot read (not JSON, not an object, a line above
    the client's limit). The connection is closed: its framing can no longer be trusted."""

    def __init__(self, message: str):
        super().__init__("protocol", message, None)


def parse_address(text: str):
    """'HOST:PORT', ':PORT', 'PORT', '[::1]:PORT' -> (host, port); 'unix:PATH' -> ('unix', PATH)."""
    if text.startswith("unix:"):
        return ("unix", text[5:])
    if text.isdigit():
        return ("127.0.0.1", int(text))
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit():
        raise ValueError(f"not HOST:PORT: {text!r}")
    host = host.strip("[]") or "127.0.0.1"
    return (host, int(port))


def _encode(obj) -> bytes:
    # allow_nan=False: JSON has no NaN or infinity; a client must not send them by accident.
    return (json.dumps(obj, separators=(",", ":"), ensure_ascii=False, allow_nan=False) + "\n").encode("utf-8")


class RowlocClient:
    """One connection to `rowloc serve`. Make it with `RowlocClient.connect(...)` (or wrap a
    connected socket: `RowlocClient(sock)`); use it as a context manager or call `close()`."""

    def __init__(self, sock: socket.socket, *, timeout: float | None = 10.0, max_line_bytes: int = 16 << 20):
        self._sock = sock
        self.timeout = timeout
        self.max_line_bytes = max_line_bytes
        self._buffer = bytearray()
        self._scan_from = 0          # bytes of _buffer already searched for a newline
        self._queue = collections.deque()   # lines not matched to a request, in arrival order
        self._next_id = 1
        self._lines_sent = 0         # newline-terminated lines written (the server's line numbers)
        self._eof = False
        self._closed = False
        self.last_hello = None

    # ----- connection -------------------------------------------------------------------------
    @classmethod
    def connect(cls, host: str = "127.0.0.1", port: int = DEFAULT_PORT, *, unix_socket: str | None = None,
                timeout: float | None = 10.0, max_line_bytes: int = 16 << 20) -> "RowlocClient":
        """Connects over TCP (host, port) or, with `unix_socket`, over that Unix socket path.
        `timeout` (seconds, None: wait forever) bounds every wait for a reply."""
        if unix_socket is not None:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.settimeout(timeout)
            try:
                sock.connect(unix_socket)
            except BaseException:
                sock.close()
                raise
        else:
            sock = socket.create_connection((host, port), timeout=timeout)
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                pass
        return cls(sock, timeout=timeout, max_line_bytes=max_line_bytes)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self) -> None:
        """Closes the connection (sessions stay open on the server: see close_session)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()

    @property
    def closed(self) -> bool:
        return self._closed

    def fileno(self) -> int:
        return self._sock.fileno()

    @property
    def lines_sent(self) -> int:
        """Lines written on this connection so far (the server's `line` numbers count the same)."""
        return self._lines_sent

    # ----- low level: writing ------------------------------------------------------------------
    def _write(self, data: bytes) -> None:
        if self._closed:
            raise ConnectionError("rowloc client: connection is closed")
        try:
            self._sock.settimeout(self.timeout)
            self._sock.sendall(data)
        except socket.timeout as e:
            raise TimeoutError("rowloc client: timed out sending to the server") from e
        self._lines_sent += data.count(b"\n")

    def send_line(self, raw) -> int:
        """Sends one raw line (str or bytes; a newline is added when missing) without waiting for
        anything: for tests of bad input. Returns its line number on this connection."""
        data = raw.encode("utf-8") if isinstance(raw, str) else bytes(raw)
        if not data.endswith(b"\n"):
            data += b"\n"
        self._write(data)
        return self._lines_sent

    def send_lines(self, lines) -> int:
        """Sends several raw lines (str or bytes, without newlines) in one write. Returns the line
        number of the last one."""
        parts = []
        for line in lines:
            b = line.encode("utf-8") if isinstance(line, str) else bytes(line)
            parts.append(b if b.endswith(b"\n") else b + b"\n")
        if parts:
            self._write(b"".join(parts))
        return self._lines_sent

    def new_id(self) -> int:
        i = self._next_id
        self._next_id += 1
        return i

    # ----- low level: reading ------------------------------------------------------------------
    def _recv_line(self, deadline: float | None) -> Message | None:
        """Next line from the socket (not the queue); None when the deadline passed first.
        Raises ConnectionError at end of stream, ProtocolError for unreadable input."""
        while True:
            nl = self._buffer.find(b"\n", self._scan_from)
            if nl >= 0:
                if nl > self.max_line_bytes:
                    self._protocol_failure(f"server line longer than {self.max_line_bytes} bytes")
                raw = bytes(self._buffer[:nl])
                del self._buffer[: nl + 1]
                self._scan_from = 0
                if raw.endswith(b"\r"):
                    raw = raw[:-1]
                if not raw.strip():
                    continue
                return self._parse(raw)
            self._scan_from = len(self._buffer)
            if len(self._buffer) > self.max_line_bytes:
                self._protocol_failure(f"server line longer than {self.max_line_bytes} bytes")
            if self._eof or self._closed:
                raise ConnectionError("rowloc client: the server closed the connection"
                                      + (" (in the middle of a line)" if self._buffer else ""))
            if deadline is None:
                self._sock.settimeout(None)
            else:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    # Past the deadline: take only what is already readable.
                    readable, _, _ = select.select([self._sock], [], [], 0)
                    if not readable:
                        return None
                    remaining = 0.001
                self._sock.settimeout(remaining)
            try:
                chunk = self._sock.recv(1 << 16)
            except (socket.timeout, BlockingIOError):
                return None
            except (ConnectionResetError, BrokenPipeError) as e:
                self._eof = True
                raise ConnectionError(f"rowloc client: connection lost ({e})") from e
            if not chunk:
                self._eof = True
                continue
            self._buffer += chunk

    def _parse(self, raw: bytes) -> Message:
        try:
            text = raw.decode("utf-8")
            value = json.loads(text)
        except (UnicodeDecodeError, ValueError) as e:
            self._protocol_failure(f"server sent a line that is not JSON ({e}): {raw[:80]!r}")
        if not isinstance(value, dict):
            self._protocol_failure(f"server sent a line that is not a JSON object: {raw[:80]!r}")
        return Message(value, text)

    def _protocol_failure(self, message: str):
        self.close()
        raise ProtocolError(message)

    def _deadline(self, timeout):
        if timeout is None:
            timeout = self.timeout
        return None if timeout is None else time.monotonic() + timeout

    # ----- requests -----------------------------------------------------------------------------
    def request(self, message: dict, *, timeout: float | None = None, raise_error: bool = True) -> Message:
        """Sends a request and returns its reply. An integer `id` is assigned unless the message
        has one. Lines that arrive meanwhile and are not the reply (pushed state or estimate
        lines, errors of other lines) are queued for read_pushed(). Raises RowlocError for an
        `error` reply (unless raise_error=False), TimeoutError when no reply came in `timeout`
        seconds (default: the client's), ConnectionError when the server closed the connection."""
        msg = dict(message)
        if "id" not in msg or msg["id"] is None:
            msg["id"] = self.new_id()
        rid = msg["id"]
        self._write(_encode(msg))
        line_no = self._lines_sent
        reply = self._wait_reply(rid, line_no, self._deadline(timeout))
        if raise_error and reply.get("type") == "error":
            raise RowlocError(str(reply.get("code")), str(reply.get("message", "")), reply)
        return reply

    def _wait_reply(self, rid, line_no: int, deadline) -> Message:
        # An earlier wait may have queued it (e.g. a timed-out request's late reply).
        for i, m in enumerate(self._queue):
            if self._is_reply(m, rid, line_no):
                del self._queue[i]
                return m
        while True:
            m = self._recv_line(deadline)
            if m is None:
                raise TimeoutError(f"rowloc client: no reply to request id {rid!r} (line {line_no})")
            if self._is_reply(m, rid, line_no):
                return m
            self._queue.append(m)

    @staticmethod
    def _is_reply(m: dict, rid, line_no: int) -> bool:
        mid = m.get("id")
        if mid is not None:
            return mid == rid and type(mid) is type(rid)
        # An error whose id the server could not read names our line number instead.
        return m.get("type") == "error" and m.get("line") == line_no

    # ----- pushed lines -------------------------------------------------------------------------
    def read_pushed(self, timeout: float | None = None) -> Message | None:
        """The next line that was not a reply (pushed `state`, `estimate_header`, `estimate`,
        `update` lines, and `error` lines of messages sent without `id`), waiting at most
        `timeout` seconds (None: the client's timeout). Returns None when nothing came."""
        if self._queue:
            return self._queue.popleft()
        return self._recv_line(self._deadline(timeout))

    def pushed(self, timeout: float = 0.0) -> list:
        """Every pushed line received so far plus those arriving within `timeout` seconds of
        silence (0: only what is already readable), removed from the queue, in order."""
        out = list(self._queue)
        self._queue.clear()
        while True:
            m = self._recv_line(time.monotonic() + timeout if timeout > 0 else time.monotonic())
            if m is None:
                return out
            out.append(m)

    def iter_pushed(self, timeout: float | None = None):
        """Yields pushed lines as they arrive; stops after `timeout` seconds without one (None:
        the client's timeout)."""
        while True:
            m = self.read_pushed(timeout)
            if m is None:
                return
            yield m

    def wait_pushed(self, predicate, timeout: float | None = None) -> Message | None:
        """The first pushed line for which predicate(line) is true (removed from the queue; the
        lines before it stay queued), or None after `timeout` seconds."""
        for i, m in enumerate(self._queue):
            if predicate(m):
                del self._queue[i]
                return m
        deadline = self._deadline(timeout)
        while True:
            m = self._recv_line(deadline)
            if m is None:
                return None
            if predicate(m):
                return m
            self._queue.append(m)

    @property
    def queued(self) -> int:
        """Number of pushed lines waiting in the queue."""
        return len(self._queue)

    # ----- the requests of docs/service.md §2 ---------------------------------------------------
    def hello(self, token: str | None = None, client: str = "python", *, protocol: str = PROTOCOL) -> Message:
        """`hello` (the first request when the server has a token). Returns the reply: `protocol`,
        `server`, `sensor_protocol`, `auth`, `limits`."""
        msg = {"type": "hello", "protocol": protocol, "client": client}
        if token is not None:
            msg["token"] = token
        self.last_hello = self.request(msg)
        return self.last_hello

    def open_session(self, vehicle: str | None = None, *, vehicle_config: dict | None = None, map: str | None = None,
                     filter: str | None = None, filter_config: dict | None = None, header: dict | None = None,
                     origin: dict | None = None, initial_pose: dict | None = None, session: str | None = None,
                     period_s: float | None = None, reorder_window_s: float | None = None) -> Message:
        """Opens a session (§3) and returns the `session_opened` reply (its `session` is the name,
        made by the server when `session` is None)."""
        msg = {"type": "open_session"}
        for key, value in (("session", session), ("vehicle", vehicle), ("vehicle_config", vehicle_config),
                           ("map", map), ("filter", filter), ("filter_config", filter_config),
                           ("header", header), ("origin", origin), ("initial_pose", initial_pose),
                           ("period_s", period_s), ("reorder_window_s", reorder_window_s)):
            if value is not None:
                msg[key] = value
        return self.request(msg)

    def close_session(self, session: str) -> Message:
        """Applies the held messages and closes the session: `session_closed` (`messages`, `journal`)."""
        return self.request({"type": "close_session", "session": session})

    def send(self, session: str, message: dict, *, ack: bool = False):
        """Sends one sensor message (a sensor-log line as a dict) to `session`. Without `ack` it
        returns at once (None; an error comes back later as a pushed `error` line); with `ack` it
        waits for the `ack` reply (`session`, `t`, `pending`) and raises RowlocError on error."""
        msg = dict(message)
        msg["session"] = session
        if ack:
            return self.request(msg)
        msg.pop("id", None)
        self._write(_encode(msg))
        return None

    def get_state(self, session: str) -> Message:
        """The session's state (§4)."""
        return self.request({"type": "get_state", "session": session})

    def subscribe(self, session: str, stream: str = "state", rate_hz: float | None = None) -> Message:
        """Subscribes this connection to `state` or `estimates` lines of a session (§5); read them
        with read_pushed()/pushed(). Returns the `subscribed` reply."""
        msg = {"type": "subscribe", "session": session, "stream": stream}
        if rate_hz is not None:
            msg["rate_hz"] = rate_hz
        return self.request(msg)

    def unsubscribe(self, session: str) -> Message:
        return self.request({"type": "unsubscribe", "session": session})

    def list_maps(self) -> Message:
        """Reply `maps`; its key `maps` lists `{"name", "rows", "segments"}`."""
        return self.request({"type": "list_maps"})

    def list_vehicles(self) -> Message:
        """Reply `vehicles`; its key `vehicles` lists `{"name", "kind", "wheels", "ultrasonic"}`."""
        return self.request({"type": "list_vehicles"})

    def list_sessions(self) -> Message:
        """Reply `sessions`; its key `sessions` lists the open sessions."""
        return self.request({"type": "list_sessions"})

    def stats(self) -> Message:
        """Reply `stats`: uptime_s, connections, sessions, messages, rejects, latency_us, dropped_states."""
        return self.request({"type": "stats"})


# ----- sensor logs --------------------------------------------------------------------------------
def read_log_header(path: str) -> dict:
    """The `log_header` (first line) of a sensor log, for open_session(header=...)."""
    with open(path, "r", encoding="utf-8") as f:
        header = json.loads(f.readline())
    if not isinstance(header, dict) or header.get("type") != "log_header":
        raise ValueError(f"{path}: the first line is not a log_header")
    return header


def read_log(path: str):
    """(header dict, [message lines as str, without newline]) of a sensor log."""
    with open(path, "r", encoding="utf-8") as f:
        header = json.loads(f.readline())
        if not isinstance(header, dict) or header.get("type") != "log_header":
            raise ValueError(f"{path}: the first line is not a log_header")
        lines = [line.rstrip("\r\n") for line in f]
    return header, [line for line in lines if line.strip()]


def add_session_key(line: str, session: str, rid=None) -> str:
    """A sensor-log line (str) with the key `session` (and `id` when given) added in front, its
    own bytes otherwise unchanged (so the numbers reach the server exactly as logged)."""
    s = line.lstrip()
    if not s.startswith("{"):
        raise ValueError(f"not a JSON object: {line[:60]!r}")
    prefix = '{"session":' + json.dumps(session)
    if rid is not None:
        prefix += ',"id":' + json.dumps(rid)
    rest = s[1:].lstrip()
    return prefix + ("}" if rest.startswith("}") else "," + rest)


def stream_log(client: RowlocClient, session: str, path, rate="max", *, start: int = 0, count: int | None = None,
               batch_bytes: int = 1 << 16, strict: bool = True) -> dict:
    """Streams the messages of a sensor log (a path, or an iterable of message lines) into an open
    session: the first line of a file is its log_header (give it to open_session(header=...)) and
    is not sent. `rate`: "max" (as fast as the socket takes them), "realtime", or a multiple of
    real time (2.0: twice as fast), paced by the messages' `t`. `start`/`count` select messages.
    The last message carries an `id`, so that the call returns when the server has taken every
    line. Returns {"sent", "first_t", "last_t", "ack", "errors"} where errors are the `error` lines
    the server sent for the streamed lines; with strict=True the first of them is raised instead.
    """
    if rate == "max":
        speed = None
    elif rate == "realtime":
        speed = 1.0
    else:
        speed = float(rate)
        if not (speed > 0 and math.isfinite(speed)):
            raise ValueError("rate must be 'max', 'realtime' or a positive number")
    if isinstance(path, (str, bytes, os.PathLike)):
        _, lines = read_log(path)
    else:
        lines = [line.rstrip("\r\n") for line in path if line.strip()]
    lines = lines[start:] if count is None else lines[start:start + count]
    result = {"sent": 0, "first_t": None, "last_t": None, "ack": None, "errors": []}
    if not lines:
        return result
    first_line = client.lines_sent + 1
    t0 = wall0 = None
    pending, pending_bytes = [], 0
    for i, line in enumerate(lines):
        last = i == len(lines) - 1
        t = None
        if speed is not None or i == 0 or last:
            t = json.loads(line).get("t")
        if i == 0:
            result["first_t"] = t
        if last:
            result["last_t"] = t
        if speed is not None and isinstance(t, (int, float)):
            if t0 is None:
                t0, wall0 = t, time.monotonic()
            due = wall0 + (t - t0) / speed
            if due > time.monotonic():
                if pending:
                    client.send_lines(pending)
                    pending, pending_bytes = [], 0
                time.sleep(max(0.0, due - time.monotonic()))
        if last:
            break
        text = add_session_key(line, session)
        pending.append(text)
        pending_bytes += len(text) + 1
        if pending_bytes >= batch_bytes:
            client.send_lines(pending)
            pending, pending_bytes = [], 0
    if pending:
        client.send_lines(pending)
    rid = client.new_id()
    client._write((add_session_key(lines[-1], session, rid) + "\n").encode("utf-8"))
    last_line = client.lines_sent
    result["sent"] = len(lines)
    try:
        result["ack"] = client._wait_reply(rid, last_line, client._deadline(None))
    finally:
        # The errors of our lines arrived before the last line's reply (one connection keeps order).
        keep = collections.deque()
        for m in client._queue:
            if (m.get("type") == "error" and m.get("id") is None
                    and isinstance(m.get("line"), int) and first_line <= m["line"] <= last_line):
                result["errors"].append(m)
            else:
                keep.append(m)
        client._queue = keep
    if result["ack"].get("type") == "error":
        result["errors"].append(result["ack"])
    if strict and result["errors"]:
        e = result["errors"][0]
        raise RowlocError(str(e.get("code")), f"{e.get('message', '')} (line {e.get('line')}; "
                                                f"{len(result['errors'])} error(s) in the stream)", e)
    return result


def _main(argv) -> int:
    import argparse
    parser = argparse.ArgumentParser(description="Smoke test of a rowloc service: hello and list_sessions.")
    parser.add_argument("address", help="HOST:PORT, or unix:PATH")
    parser.add_argument("--token", help="token of a server started with --token-file")
    parser.add_argument("--timeout", type=float, default=10.0)
    args = parser.parse_args(argv)
    host, port = parse_address(args.address)
    try:
        if host == "unix":
            client = RowlocClient.connect(unix_socket=port, timeout=args.timeout)
        else:
            client = RowlocClient.connect(host, port, timeout=args.timeout)
        with client:
            print(json.dumps(client.hello(token=args.token, client="rowloc_client.py")))
            print(json.dumps(client.list_sessions()))
    except RowlocError as e:
        print(f"rowloc_client: error {e}", file=sys.stderr)
        return 1
    except (OSError, TimeoutError) as e:
        print(f"rowloc_client: {args.address}: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
