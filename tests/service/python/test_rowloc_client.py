"""Tests of service/python/rowloc_client.py against a real `rowloc serve` (docs/service.md).

Standard library only. Environment: ROWLOC_BIN (the rowloc executable), ROWLOC_SOURCE_DIR (the
source tree: config/vehicles, maps, config/filters, config/scenarios), PYTHONPATH with
service/python. Every test starts its own server on a free loopback port (--port 0) and stops it
in tearDown (SIGTERM, then SIGKILL after 10 s). The sensor logs are made once by
`rowloc simulate config/scenarios/vineyard-002-4us.json` (setUpModule) and cut to their first
messages.
"""

import glob
import json
import math
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

from rowloc_client import (Message, ProtocolError, RowlocClient, RowlocError, add_session_key, read_log,
                           stream_log)

ROWLOC = os.environ.get("ROWLOC_BIN")
SRC = os.environ.get("ROWLOC_SOURCE_DIR")
CLIENT_PY = os.path.join(SRC or ".", "service", "python", "rowloc_client.py")

VEHICLE = "vineyard-ugv-4ws"
MAP = "sample-vineyard"
MAIN_MESSAGES = 10000     # t = 0 .. 40.8 s; the filter initialises from GNSS at t = 16.6 s (line 4069)
SHORT_MESSAGES = 1500     # t = 0 .. 6.1 s, with an initial pose
WINDOW = 0.2              # the server's default reorder window

_TMP = None
LOG = {}                  # name -> {"path", "header", "lines"}
TRUTH = []                # (t, x, y, phi) of the first 45 s
INITIAL_POSE = None
_PROCESSES = []           # every server started, killed in tearDownModule if still running


def setUpModule():
    global _TMP, INITIAL_POSE
    if not ROWLOC or not SRC:
        raise unittest.SkipTest("set ROWLOC_BIN and ROWLOC_SOURCE_DIR")
    if not os.access(ROWLOC, os.X_OK):
        raise unittest.SkipTest(f"ROWLOC_BIN={ROWLOC} is not an executable")
    _TMP = tempfile.mkdtemp(prefix="rowloc-pyclient-")
    run = os.path.join(_TMP, "sim")
    scenario = os.path.join(SRC, "config", "scenarios", "vineyard-002-4us.json")
    r = subprocess.run([ROWLOC, "simulate", scenario, "-o", run, "--no-baselines"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300)
    if r.returncode != 0:
        raise RuntimeError("rowloc simulate failed:\n" + r.stdout.decode(errors="replace")[-3000:])
    with open(os.path.join(run, "sensors.ndjson"), encoding="utf-8") as f:
        header_line = f.readline().rstrip("\n")
        lines = []
        for line in f:
            lines.append(line.rstrip("\n"))
            if len(lines) >= MAIN_MESSAGES:
                break
    for name, n in (("main", MAIN_MESSAGES), ("short", SHORT_MESSAGES)):
        path = os.path.join(_TMP, name + ".ndjson")
        with open(path, "w", encoding="utf-8") as f:
            f.write(header_line + "\n")
            for line in lines[:n]:
                f.write(line + "\n")
        LOG[name] = {"path": path, "header": json.loads(header_line), "lines": lines[:n]}
    with open(os.path.join(run, "truth.ndjson"), encoding="utf-8") as f:
        f.readline()
        for line in f:
            m = json.loads(line)
            if m["t"] > 45.0:
                break
            TRUTH.append((m["t"], m["x_m"], m["y_m"], m["phi_rad"]))
    os.remove(os.path.join(run, "truth.ndjson"))
    os.remove(os.path.join(run, "sensors.ndjson"))
    t0, x0, y0, phi0 = TRUTH[0]
    INITIAL_POSE = {"t": t0, "x_m": x0, "y_m": y0, "phi_rad": phi0, "sigma_xy_m": 0.3, "sigma_phi_rad": 0.05}


def tearDownModule():
    for proc in _PROCESSES:
        if proc.poll() is None:
            print(f"warning: a rowloc serve process was still running: {proc.args}", file=sys.stderr)
            proc.kill()
            proc.wait(10)
    if _TMP:
        shutil.rmtree(_TMP, ignore_errors=True)


# ----- small helpers -------------------------------------------------------------------------------
def cholesky(a):
    """Cholesky factor of a symmetric matrix (list of rows); raises ValueError unless positive definite."""
    n = len(a)
    lower = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = a[i][j] - sum(lower[i][k] * lower[j][k] for k in range(j))
            if i == j:
                if not s > 0.0:
                    raise ValueError(f"not positive definite (pivot {i}: {s})")
                lower[i][i] = math.sqrt(s)
            else:
                lower[i][j] = s / lower[j][j]
    return lower


def finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def msg_t(line):
    return json.loads(line)["t"]


def without(d, *keys):
    return {k: v for k, v in d.items() if k not in keys}


def truth_at(t):
    best = min(TRUTH, key=lambda r: abs(r[0] - t))
    return best


class Server:
    """A `rowloc serve` process on a free loopback port."""

    def __init__(self, workdir, *, config=None, args=(), journal_dir=None, vehicles_dir=None, maps_dir=None,
                 expect_listening=True):
        self.workdir = workdir
        self.journal_dir = journal_dir or os.path.join(workdir, "journal")
        os.makedirs(self.journal_dir, exist_ok=True)
        cmd = [ROWLOC, "serve", "--port", "0",
               "--vehicles", vehicles_dir or os.path.join(SRC, "config", "vehicles"),
               "--maps", maps_dir or os.path.join(SRC, "maps"),
               "--filters", os.path.join(SRC, "config", "filters"),
               "--journal-dir", self.journal_dir]
        if config is not None:
            path = os.path.join(workdir, f"serve-config-{id(self)}.json")
            with open(path, "w") as f:
                json.dump(config, f)
            cmd += ["--config", path]
        cmd += list(args)
        self.cmd = cmd
        self.stderr_path = os.path.join(workdir, f"serve-{id(self)}.stderr")
        self._stderr = open(self.stderr_path, "wb")
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=self._stderr)
        _PROCESSES.append(self.proc)
        self.killed = False
        self.stopped = False
        self.listening = None
        self.port = None
        self.unix = None
        if expect_listening:
            try:
                self._read_listening()
            except BaseException:
                self.proc.kill()
                self.proc.wait(10)
                raise

    def _read_listening(self):
        deadline = time.monotonic() + 30
        buf = b""
        fd = self.proc.stdout.fileno()
        while b"\n" not in buf:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError("rowloc serve printed no listening line in 30 s\n" + self.stderr_tail())
            r, _, _ = select.select([fd], [], [], remaining)
            if r:
                chunk = os.read(fd, 4096)
                if not chunk:
                    self.proc.wait(5)
                    raise AssertionError(f"rowloc serve exited ({self.proc.returncode}) before listening: "
                                         f"{' '.join(self.cmd)}\n" + self.stderr_tail())
                buf += chunk
        first, _, rest = buf.partition(b"\n")
        self.listening = json.loads(first)
        assert self.listening.get("type") == "listening", self.listening
        host, _, port = self.listening["tcp"].rpartition(":")
        self.host, self.port = host, int(port)
        self.unix = self.listening.get("unix")
        # Nothing else should come on stdout, but never let a full pipe block the server.
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self):
        try:
            while self.proc.stdout.read(65536):
                pass
        except (OSError, ValueError):
            pass

    def stderr_tail(self, n=4000):
        if not self._stderr.closed:
            self._stderr.flush()
        try:
            with open(self.stderr_path, "rb") as f:
                return f.read().decode(errors="replace")[-n:]
        except OSError:
            return ""

    def connect(self, timeout=20.0, **kw):
        return RowlocClient.connect("127.0.0.1", self.port, timeout=timeout, **kw)

    def kill9(self):
        self.killed = True
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)

    def terminate(self):
        """SIGTERM from the test itself; stop() then checks the exit status."""
        self.terminated = True
        self.proc.send_signal(signal.SIGTERM)

    def stop(self):
        """SIGTERM, then SIGKILL after 10 s. Returns a problem description or None."""
        problem = None
        if self.stopped:
            return None
        self.stopped = True
        if getattr(self, "terminated", False):
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                pass
        if self.proc.poll() is not None:
            if getattr(self, "terminated", False):
                if self.proc.returncode not in (0, -signal.SIGTERM, 128 + signal.SIGTERM):
                    problem = f"rowloc serve exited with status {self.proc.returncode} on SIGTERM"
            elif not self.killed:
                problem = f"rowloc serve had exited on its own with status {self.proc.returncode}"
        else:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
                if self.proc.returncode not in (0, -signal.SIGTERM, 128 + signal.SIGTERM):
                    problem = f"rowloc serve exited with status {self.proc.returncode} on SIGTERM"
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
                problem = "rowloc serve did not exit within 10 s of SIGTERM (killed)"
        try:
            self.proc.stdout.close()
        except OSError:
            pass
        self._stderr.close()
        assert self.proc.poll() is not None
        return problem


class ServiceTestCase(unittest.TestCase):
    maxDiff = 4000

    def assertConnections(self, client, count, timeout_s=2.0):
        """The server's connection count reaches `count` within timeout_s. A closed connection is
        counted until its coroutine has finished closing it, which may be a moment after the client
        sees the end of the stream (CI under ASan once saw the old count)."""
        deadline = time.monotonic() + timeout_s
        while client.stats()["connections"] != count and time.monotonic() < deadline:
            time.sleep(0.02)
        self.assertEqual(client.stats()["connections"], count)

    def setUp(self):
        self.workdir = tempfile.mkdtemp(prefix="t-", dir=_TMP)
        self._servers = []
        self._clients = []

    def tearDown(self):
        for c in self._clients:
            try:
                c.close()
            except OSError:
                pass
        problems = []
        for s in self._servers:
            p = s.stop()
            if p:
                problems.append(p + "\n" + s.stderr_tail(2000))
        shutil.rmtree(self.workdir, ignore_errors=True)
        if problems:
            self.fail("\n".join(problems))

    # -- helpers
    def server(self, **kw):
        s = Server(self.workdir, **kw)
        self._servers.append(s)
        return s

    def client(self, server, hello=True, **kw):
        c = server.connect(**kw)
        self._clients.append(c)
        if hello:
            c.hello()
        return c

    def open_main(self, c, session, *, log="main", **kw):
        kw.setdefault("map", MAP)
        return c.open_session(VEHICLE, header=LOG[log]["header"], session=session, **kw)

    def assertAlive(self, c, session=None):
        """The connection (and the session) still work after an error."""
        if session is None:
            reply = c.hello()
            self.assertEqual(reply["type"], "hello")
        else:
            st = c.get_state(session)
            self.assertEqual(st["type"], "state")
            self.assertEqual(st["session"], session)

    def expect_error(self, c, line, code, *, rid=None, session=None):
        """Sends one raw line (str, or a dict encoded as JSON) and checks the error reply (§7): its
        code, its id (the request's, or null), its line number; then that the connection lives."""
        raw = line if isinstance(line, (str, bytes)) else json.dumps(line, separators=(",", ":"))
        n = c.send_line(raw)
        m = c.read_pushed(timeout=15)
        shown = raw if len(raw) < 200 else raw[:200] + "..."
        self.assertIsNotNone(m, f"no reply to {shown}")
        self.assertEqual(m.get("type"), "error", f"request {shown}: got {m.raw[:500]}")
        self.assertEqual(m.get("code"), code, f"request {shown}: got {m.raw[:500]}")
        self.assertEqual(m.get("id"), rid, f"request {shown}: got {m.raw[:500]}")
        self.assertEqual(m.get("line"), n, f"request {shown}: got {m.raw[:500]}")
        self.assertIsInstance(m.get("message"), str)
        self.assertTrue(m["message"], m.raw)
        self.assertAlive(c, session)
        return m

    def check_state(self, st, session, wheels=None, initialised=True):
        self.assertEqual(st["type"], "state", st)
        self.assertEqual(st["session"], session)
        self.assertIs(st["initialised"], initialised, st)
        health = st["health"]
        self.assertIsInstance(health["pending"], int)
        self.assertGreaterEqual(health["pending"], 0)
        self.assertIsInstance(health["rejected_messages"], int)
        self.assertIsInstance(health["sensors"], dict)
        if not initialised:
            self.assertLessEqual(set(st), {"type", "id", "session", "t", "initialised", "health"}, st)
            return
        for key in ("t", "x_m", "y_m", "phi_rad", "latitude_deg", "longitude_deg"):
            self.assertTrue(finite(st[key]), f"{key}: {st.get(key)}")
        self.assertLessEqual(abs(st["phi_rad"]), math.pi + 1e-12)
        cov = st["covariance_xy_phi"]
        self.assertEqual(len(cov), 9)
        self.assertTrue(all(finite(v) for v in cov), cov)
        m = [cov[0:3], cov[3:6], cov[6:9]]
        for i in range(3):
            for j in range(3):
                self.assertLessEqual(abs(m[i][j] - m[j][i]), 1e-12 * max(1.0, abs(m[i][j])), f"asymmetric {cov}")
        cholesky(m)   # positive definite, or ValueError
        # The 2-sigma ellipse of the position (semi-axes 2 sqrt(eigenvalues), major axis from +East).
        a, b, c = m[0][0], m[0][1], m[1][1]
        mean, d = (a + c) / 2, math.hypot((a - c) / 2, b)
        e = st["ellipse_2sigma"]
        self.assertAlmostEqual(e["semi_major_m"], 2 * math.sqrt(mean + d), delta=1e-6 * e["semi_major_m"] + 1e-12)
        self.assertAlmostEqual(e["semi_minor_m"], 2 * math.sqrt(mean - d), delta=1e-6 * e["semi_major_m"] + 1e-12)
        if d > 1e-6 * mean:
            angle = 0.5 * math.atan2(2 * b, a - c)
            diff = (e["angle_rad"] - angle) % math.pi
            self.assertLess(min(diff, math.pi - diff), 1e-4, e)
        for key in ("x_mps", "y_mps", "yaw_rate_radps"):
            self.assertTrue(finite(st["velocity"][key]), st["velocity"])
        if wheels is not None:
            self.assertEqual(set(st["slip"]), set(wheels))
        self.assertTrue(all(finite(v) for v in st["slip"].values()), st["slip"])
        # latitude/longitude of the local position (ENU at the log's origin).
        o = LOG["main"]["header"]["origin"]
        lat0 = math.radians(o["latitude_deg"])
        a_wgs, e2 = 6378137.0, 6.69437999014e-3
        w = math.sqrt(1 - e2 * math.sin(lat0) ** 2)
        meridian, normal = a_wgs * (1 - e2) / w ** 3, a_wgs / w
        self.assertAlmostEqual(st["latitude_deg"], o["latitude_deg"] + math.degrees(st["y_m"] / meridian), delta=2e-7)
        self.assertAlmostEqual(st["longitude_deg"],
                               o["longitude_deg"] + math.degrees(st["x_m"] / (normal * math.cos(lat0))), delta=2e-7)


# ----- hello, lists, sessions ------------------------------------------------------------------------
class TestHelloAndSessions(ServiceTestCase):
    def test_hello_and_lists(self):
        s = self.server()
        c = self.client(s, hello=False)
        h = c.hello(client="unittest")
        self.assertEqual(h["type"], "hello")
        self.assertEqual(h["protocol"], "rowloc-service/1")
        self.assertEqual(h["sensor_protocol"], "rowloc/1")
        self.assertEqual(h["auth"], "none")
        self.assertIsInstance(h["server"], str)
        self.assertIsInstance(h["limits"], dict)
        self.assertIsInstance(h["id"], int)
        # The reply repeats a string id; a later minor version of the protocol is accepted.
        r = c.request({"type": "hello", "id": "hello-1", "protocol": "rowloc-service/1.9"})
        self.assertEqual((r["type"], r["id"]), ("hello", "hello-1"))
        r = c.request({"type": "hello"})      # protocol and client are optional
        self.assertEqual(r["type"], "hello")

        maps = c.list_maps()
        self.assertEqual(maps["type"], "maps")
        entry = [m for m in maps["maps"] if m["name"] == MAP]
        self.assertEqual(len(entry), 1, maps)
        self.assertEqual(entry[0]["rows"], 10)
        self.assertGreater(entry[0]["segments"], 10)

        vehicles = c.list_vehicles()
        self.assertEqual(vehicles["type"], "vehicles")
        names = {v["name"]: v for v in vehicles["vehicles"]}
        for name in ("vineyard-ugv-4ws", "agrimaro-swerve", "differential", "tracked", "vineyard-ugv-4ws-8us"):
            self.assertIn(name, names)
        self.assertEqual(names[VEHICLE]["kind"], "four_wheel_steer")
        for key in ("wheels", "ultrasonic"):
            self.assertIn(key, names[VEHICLE])

        sessions = c.list_sessions()
        self.assertEqual(sessions["type"], "sessions")
        self.assertEqual(sessions["sessions"], [])

        st = c.stats()
        self.assertEqual(st["type"], "stats")
        for key in ("uptime_s", "connections", "sessions", "messages", "dropped_states"):
            self.assertTrue(finite(st[key]), f"{key}: {st.get(key)}")
        self.assertGreaterEqual(st["connections"], 1)
        self.assertEqual(st["sessions"], 0)
        self.assertIsInstance(st["rejects"], dict)
        for key in ("p50", "p90", "p99", "max"):
            self.assertIn(key, st["latency_us"])

    def test_open_and_close_session_by_name(self):
        s = self.server()
        c = self.client(s)
        opened = self.open_main(c, "ugv1")
        self.assertEqual(opened["type"], "session_opened")
        self.assertEqual(opened["session"], "ugv1")
        # No filter named: the one the vehicle file recommends (recommended_filter, docs/service.md §3).
        self.assertEqual((opened["filter"], opened["filter_source"]), ("default", "vehicle"))
        listed = {x["session"]: x for x in c.list_sessions()["sessions"]}
        self.assertEqual(listed["ugv1"]["vehicle"], VEHICLE)
        self.assertEqual(listed["ugv1"]["map"], MAP)
        self.assertEqual(listed["ugv1"]["messages"], 0)
        self.assertIs(listed["ugv1"]["initialised"], False)
        for key in ("t", "subscribers"):
            self.assertIn(key, listed["ugv1"])
        # Before initialisation: only session, t, initialised and health.
        self.check_state(c.get_state("ugv1"), "ugv1", initialised=False)
        self.assertTrue(os.path.exists(os.path.join(s.journal_dir, "ugv1.ndjson")))
        self.assertTrue(os.path.exists(os.path.join(s.journal_dir, "ugv1.session.json")))
        # A session is not tied to its connection: another connection reads and closes it.
        c2 = self.client(s)
        self.assertEqual(c2.get_state("ugv1")["session"], "ugv1")
        closed = c2.close_session("ugv1")
        self.assertEqual(closed["type"], "session_closed")
        self.assertEqual(closed["session"], "ugv1")
        self.assertEqual(closed["messages"], 0)
        self.assertIsInstance(closed["journal"], str)
        self.assertEqual(c.list_sessions()["sessions"], [])
        self.assertFalse(os.path.exists(os.path.join(s.journal_dir, "ugv1.ndjson")))
        self.assertFalse(os.path.exists(os.path.join(s.journal_dir, "ugv1.session.json")))
        self.assertTrue(os.path.isfile(closed["journal"]), closed["journal"])
        with self.assertRaises(RowlocError) as cm:
            c.get_state("ugv1")
        self.assertEqual(cm.exception.code, "unknown_session")
        # The name may be used again once closed; without a name the server makes one.
        self.assertEqual(self.open_main(c, "ugv1", filter="canopy-gnss-flat")["session"], "ugv1")
        auto = c.open_session(VEHICLE, map=MAP)
        self.assertRegex(auto["session"], r"^[A-Za-z0-9._-]{1,64}$")
        self.assertNotEqual(auto["session"], "ugv1")
        # Inline vehicle and filter, an explicit origin instead of header and map.
        with open(os.path.join(SRC, "config", "vehicles", "differential.json")) as f:
            vehicle_config = json.load(f)
        with open(os.path.join(SRC, "config", "filters", "differential.json")) as f:
            filter_config = json.load(f)
        inline = c.open_session(vehicle_config=vehicle_config, filter_config=filter_config,
                                origin={"latitude_deg": 45.0, "longitude_deg": 7.0, "altitude_m": 200.0},
                                session="inline.1", period_s=0.5, reorder_window_s=0.5)
        self.assertEqual(inline["session"], "inline.1")
        self.assertEqual((inline["filter"], inline["filter_source"]), (None, "given"))
        for name in ("ugv1", auto["session"], "inline.1"):
            self.assertEqual(c.close_session(name)["session"], name)

    def test_closed_journal_file_names(self):
        """§8: a closed session's files move to closed/SESSION-N.ndjson and .session.json."""
        s = self.server()
        c = self.client(s)
        for n in (1, 2):
            self.open_main(c, "ugv1")
            closed = c.close_session("ugv1")
            closed_dir = os.path.join(s.journal_dir, "closed")
            self.assertEqual(os.path.realpath(closed["journal"]),
                             os.path.realpath(os.path.join(closed_dir, f"ugv1-{n}.ndjson")))
            self.assertTrue(os.path.isfile(os.path.join(closed_dir, f"ugv1-{n}.ndjson")))
            self.assertTrue(os.path.isfile(os.path.join(closed_dir, f"ugv1-{n}.session.json")))
            self.assertFalse(os.path.exists(os.path.join(s.journal_dir, "ugv1.ndjson")))

    def test_unix_socket(self):
        path = os.path.join(self.workdir, "rowloc.sock")
        s = self.server(args=["--unix-socket", path])
        self.assertEqual(s.unix, path)
        with RowlocClient.connect(unix_socket=path, timeout=20) as c:
            self.assertEqual(c.hello()["type"], "hello")
            self.assertEqual(c.list_sessions()["sessions"], [])

    def test_smoke_main(self):
        s = self.server()
        r = subprocess.run([sys.executable, CLIENT_PY, f"127.0.0.1:{s.port}"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, timeout=60, env=dict(os.environ, PYTHONDONTWRITEBYTECODE="1"))
        self.assertEqual(r.returncode, 0, r.stderr)
        out = [json.loads(x) for x in r.stdout.decode().splitlines()]
        self.assertEqual([m["type"] for m in out], ["hello", "sessions"])


# ----- streaming and state ---------------------------------------------------------------------------
class TestStreaming(ServiceTestCase):
    def test_stream_log_and_get_state(self):
        s = self.server()
        c = self.client(s)
        self.open_main(c, "run1")
        result = stream_log(c, "run1", LOG["main"]["path"])
        self.assertEqual(result["sent"], MAIN_MESSAGES)
        self.assertEqual(result["errors"], [])
        self.assertEqual(result["ack"]["type"], "ack")
        self.assertEqual(result["ack"]["session"], "run1")
        self.assertEqual(result["ack"]["t"], msg_t(LOG["main"]["lines"][-1]))
        st = c.get_state("run1")
        wheels = LOG["main"]["header"]["wheels"]
        self.check_state(st, "run1", wheels)
        # The state answers for the messages up to one window before the newest.
        last_t = msg_t(LOG["main"]["lines"][-1])
        self.assertLessEqual(st["t"], last_t - WINDOW + 1e-9)
        self.assertGreater(st["t"], last_t - WINDOW - 0.1)
        self.assertGreater(st["health"]["pending"], 0)
        gnss = st["health"]["sensors"]["gnss"]
        self.assertGreater(gnss["accepted"], 50)
        self.assertTrue(finite(gnss["last_nis"]))
        self.assertTrue(finite(st["health"]["last_fix_age_s"]))
        # Against the truth (SBAS fixes, sigma 0.6 m).
        tt, tx, ty, tphi = truth_at(st["t"])
        self.assertLess(math.hypot(st["x_m"] - tx, st["y_m"] - ty), 3.0, (st, tt, tx, ty))
        listed = {x["session"]: x for x in c.list_sessions()["sessions"]}["run1"]
        self.assertEqual(listed["messages"], MAIN_MESSAGES)
        self.assertIs(listed["initialised"], True)
        closed = c.close_session("run1")
        self.assertEqual(closed["messages"], MAIN_MESSAGES)

    def test_ack_and_send(self):
        s = self.server()
        c = self.client(s)
        self.open_main(c, "a1", log="short", initial_pose=INITIAL_POSE)
        lines = LOG["short"]["lines"]
        first = json.loads(lines[0])
        ack = c.send("a1", first, ack=True)
        self.assertEqual(ack["type"], "ack")
        self.assertEqual(ack["session"], "a1")
        self.assertEqual(ack["t"], first["t"])
        self.assertIsInstance(ack["pending"], int)
        for line in lines[1:200]:
            self.assertIsNone(c.send("a1", json.loads(line)))
        ack = c.send("a1", json.loads(lines[200]), ack=True)
        self.assertEqual(ack["t"], msg_t(lines[200]))
        self.assertEqual(c.pushed(), [])          # nothing but the replies came back
        # Unknown keys are ignored (a later minor version only adds keys); ids up to 128 characters.
        extra = dict(json.loads(lines[201]), future_key={"a": [1, 2]})
        self.assertEqual(c.send("a1", extra, ack=True)["type"], "ack")
        self.assertEqual(c.request({"type": "get_state", "session": "a1", "future": 1, "id": "i" * 128})["id"], "i" * 128)
        self.assertEqual(c.close_session("a1")["messages"], 202)

    def test_stream_log_pacing(self):
        s = self.server()
        c = self.client(s)
        self.open_main(c, "p1", log="short", initial_pose=INITIAL_POSE)
        lines = LOG["short"]["lines"]
        n = next(i for i, x in enumerate(lines) if msg_t(x) >= 0.3)   # 0.3 s of log time
        start = time.monotonic()
        r = stream_log(c, "p1", lines[:n], rate="realtime")
        took = time.monotonic() - start
        span = r["last_t"] - r["first_t"]
        self.assertGreaterEqual(took, span - 0.02)
        self.assertLess(took, span + 2.0)
        start = time.monotonic()
        r = stream_log(c, "p1", lines[n:2 * n], rate=3.0)
        took = time.monotonic() - start
        span = r["last_t"] - r["first_t"]
        self.assertGreaterEqual(took, span / 3.0 - 0.02)
        self.assertEqual(c.close_session("p1")["messages"], 2 * n)

    def test_subscribe_state(self):
        s = self.server()
        c = self.client(s)
        lines = LOG["short"]["lines"]
        self.open_main(c, "sub1", log="short", initial_pose=INITIAL_POSE)
        sub = c.subscribe("sub1")
        self.assertEqual(sub["type"], "subscribed")
        self.assertEqual({x["session"]: x for x in c.list_sessions()["sessions"]}["sub1"]["subscribers"], 1)
        stream_log(c, "sub1", lines[:1000])
        st = c.get_state("sub1")
        pushed = c.pushed(timeout=0.5)
        states = [m for m in pushed if m.get("type") == "state"]
        self.assertEqual(len(states), len(pushed), [m.raw for m in pushed if m.get("type") != "state"][:3])
        self.assertGreater(len(states), 300)          # after every message that changed the filter
        times = [m["t"] for m in states]
        self.assertEqual(times, sorted(times))
        for m in states:
            self.assertNotIn("id", m)
            self.assertEqual(m["session"], "sub1")
        self.check_state(states[-1], "sub1", LOG["short"]["header"]["wheels"])
        # the last pushed state is the state (only `pending` may have grown since: messages held
        # in the window change no filter state)
        self.assertEqual(without(states[-1], "id", "dropped", "health"), without(st, "id", "health"))
        self.assertLessEqual(states[-1]["t"], st["t"])
        # unsubscribe: no more state lines.
        self.assertEqual(c.unsubscribe("sub1")["type"], "unsubscribed")
        c.pushed(timeout=0.2)
        stream_log(c, "sub1", lines[1000:1200])
        c.get_state("sub1")
        self.assertEqual(c.pushed(timeout=0.3), [])

        # rate_hz 0 is the same as no rate
        self.open_main(c, "sub0", log="short", initial_pose=INITIAL_POSE)
        c.subscribe("sub0", "state", rate_hz=0)
        stream_log(c, "sub0", lines[:300])
        c.get_state("sub0")
        self.assertGreater(len([m for m in c.pushed(timeout=0.3) if m.get("type") == "state"]), 100)
        # rate_hz: at most that many lines per second of log time.
        self.open_main(c, "sub2", log="short", initial_pose=INITIAL_POSE)
        c.subscribe("sub2", "state", rate_hz=2)
        r = stream_log(c, "sub2", lines)
        c.get_state("sub2")
        states = [m for m in c.pushed(timeout=0.5) if m.get("type") == "state"]
        span = r["last_t"] - r["first_t"]
        self.assertGreaterEqual(len(states), 2)
        self.assertLessEqual(len(states), 2 * span + 2, [m["t"] for m in states])
        gaps = [b["t"] - a["t"] for a, b in zip(states, states[1:])]
        self.assertGreaterEqual(min(gaps), 0.5 - 1e-6, gaps)

    def test_subscribed_reply_comes_first(self):
        """§2: subscribe is answered by `subscribed`, then the pushed lines."""
        s = self.server()
        c = self.client(s)
        self.open_main(c, "o1", log="short", initial_pose=INITIAL_POSE)
        c.send_line('{"type":"subscribe","id":"sub","session":"o1","stream":"estimates"}')
        first, second = c.read_pushed(10), c.read_pushed(10)
        self.assertEqual((first["type"], first.get("id")), ("subscribed", "sub"), first.raw)
        self.assertEqual(second["type"], "estimate_header", second.raw)

    def test_subscribe_estimates(self):
        s = self.server()
        c = self.client(s)
        lines = LOG["short"]["lines"]
        for name, period in (("est1", None), ("est2", 0.5)):
            self.open_main(c, name, log="short", initial_pose=INITIAL_POSE, period_s=period)
            self.assertEqual(c.subscribe(name, stream="estimates")["type"], "subscribed")
            stream_log(c, name, lines)
            c.close_session(name)
            pushed = c.pushed(timeout=0.5)
            self.assertGreater(len(pushed), 10)
            self.assertEqual(pushed[0]["type"], "estimate_header", pushed[0].raw)
            self.assertEqual(pushed[0]["protocol"], "rowloc-estimate/1")
            suffix = ',"session":' + json.dumps(name) + "}"
            types = set()
            for m in pushed:
                self.assertTrue(m.raw.endswith(suffix), m.raw[-80:])
                self.assertNotIn("id", m)
                types.add(m["type"])
            self.assertEqual(types, {"estimate_header", "estimate", "update"})
            est = [m for m in pushed if m["type"] == "estimate"]
            gaps = [b["t"] - a["t"] for a, b in zip(est, est[1:])]
            self.assertAlmostEqual(min(gaps), period or 0.1, delta=1e-6)
            span = msg_t(lines[-1]) - msg_t(lines[0])
            self.assertLessEqual(len(est), span / (period or 0.1) + 2)
            for m in est:
                self.assertTrue(finite(m["x_m"]) and finite(m["y_m"]))
                cholesky([m["covariance_xy_phi"][0:3], m["covariance_xy_phi"][3:6], m["covariance_xy_phi"][6:9]])

    def test_many_sessions(self):
        """50 sessions over 4 connections, their messages interleaved: each ends in the state of the
        same log streamed alone."""
        s = self.server()
        lines = LOG["short"]["lines"]
        c = self.client(s)
        self.open_main(c, "ref", log="short", initial_pose=INITIAL_POSE)
        stream_log(c, "ref", lines)
        ref = c.get_state("ref")
        self.check_state(ref, "ref", LOG["short"]["header"]["wheels"])
        names = [f"m{i:02d}" for i in range(50)]
        states, errors, failures = {}, [], []

        def worker(k):
            try:
                with s.connect(timeout=60) as w:
                    w.hello(client=f"worker{k}")
                    mine = names[k::4]
                    for name in mine:
                        self.open_main(w, name, log="short", initial_pose=INITIAL_POSE)
                    batch = []
                    for line in lines:
                        for name in mine:
                            batch.append(add_session_key(line, name))
                        if len(batch) >= 500:
                            w.send_lines(batch)
                            batch = []
                    w.send_lines(batch)
                    for name in mine:
                        states[name] = w.get_state(name)
                    errors.extend(w.pushed())
            except Exception as e:   # noqa: BLE001 - reported below
                failures.append(f"worker {k}: {e!r}")

        threads = [threading.Thread(target=worker, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        self.assertEqual(failures, [])
        self.assertEqual(errors, [])
        self.assertEqual(sorted(states), names)
        for name in names:
            self.assertEqual(without(states[name], "id", "session"), without(ref, "id", "session"), name)
        listed = {x["session"]: x for x in c.list_sessions()["sessions"]}
        self.assertEqual(len(listed), 51)
        for name in names:
            self.assertEqual(listed[name]["messages"], len(lines))
        stats = c.stats()
        self.assertEqual(stats["sessions"], 51)
        self.assertGreaterEqual(stats["messages"], 51 * len(lines))
        lat = stats["latency_us"]
        self.assertLessEqual(lat["p50"], lat["p90"])
        self.assertLessEqual(lat["p90"], lat["p99"])
        self.assertLessEqual(lat["p99"], lat["max"])
        for name in names:
            self.assertEqual(c.close_session(name)["messages"], len(lines))


# ----- time: reorder window and too_old --------------------------------------------------------------
class TestReorderWindow(ServiceTestCase):
    def test_late_gps_fix_is_used(self):
        """GPS fixes that arrive after IMU, wheel and steering messages up to 0.15 s newer are used:
        the state equals that of the same messages in time order."""
        lines = LOG["main"]["lines"]
        late, delayed = [], 0
        held = []   # (release time, line)
        for line in lines:
            t = msg_t(line)
            while held and held[0][0] < t:
                late.append(held.pop(0)[1])
            if '"type":"gps"' in line and 17.0 < t < msg_t(lines[-1]) - 0.3:
                held.append((t + 0.15, line))
                delayed += 1
            else:
                late.append(line)
        late.extend(h[1] for h in held)
        self.assertGreater(delayed, 30)
        in_order = sorted(late, key=msg_t)   # stable: equal times keep their arrival order
        self.assertNotEqual(late, in_order)

        s = self.server()
        c = self.client(s)
        self.open_main(c, "late")
        self.open_main(c, "ordered")
        self.open_main(c, "nowindow", reorder_window_s=0)
        r = stream_log(c, "late", late)
        self.assertEqual(r["errors"], [])
        stream_log(c, "ordered", in_order)
        a, b = c.get_state("late"), c.get_state("ordered")
        self.check_state(a, "late")
        self.assertEqual(without(a, "id", "session"), without(b, "id", "session"))
        accepted = a["health"]["sensors"]["gnss"]["accepted"]
        self.assertGreater(accepted, delayed - 5)
        # Without a window the late fixes are refused (too_old) and not used.
        r = stream_log(c, "nowindow", late, strict=False)
        codes = [e["code"] for e in r["errors"]]
        self.assertEqual(codes, ["too_old"] * delayed, codes[:5])
        n = c.get_state("nowindow")
        self.assertLess(n["health"]["sensors"]["gnss"]["accepted"], accepted - delayed // 2)
        # close_session applies every held message; refused messages are not counted.
        self.assertEqual(c.close_session("late")["messages"], MAIN_MESSAGES)
        self.assertEqual(c.close_session("nowindow")["messages"], MAIN_MESSAGES - delayed)

    def test_too_old_and_pending(self):
        s = self.server()
        c = self.client(s)
        imu = {"type": "imu", "sensor": "imu", "accel_x_mps2": 0.0, "accel_y_mps2": 0.0, "gyro_z_radps": 0.0}

        def at(t):
            return dict(imu, t=t)

        self.open_main(c, "w0", initial_pose=INITIAL_POSE, reorder_window_s=0)
        self.assertEqual(c.send("w0", at(1.0), ack=True)["pending"], 0)
        with self.assertRaises(RowlocError) as cm:
            c.send("w0", at(0.5), ack=True)
        self.assertEqual(cm.exception.code, "too_old")
        self.assertAlive(c, "w0")
        self.assertEqual(c.send("w0", at(1.0), ack=True)["pending"], 0)   # equal times are fine

        self.open_main(c, "w2", initial_pose=INITIAL_POSE)                # default window 0.2 s
        self.assertEqual(c.send("w2", at(2.0), ack=True)["pending"], 1)
        self.assertEqual(c.send("w2", at(2.5), ack=True)["pending"], 1)   # 2.0 given to the filter
        self.assertEqual(c.send("w2", at(2.4), ack=True)["pending"], 2)   # inside the window: held
        self.assertEqual(c.send("w2", at(2.1), ack=True)["pending"], 2)   # 0.4 s older than 2.5: applied
        with self.assertRaises(RowlocError) as cm:
            c.send("w2", at(2.05), ack=True)                               # older than 2.1
        self.assertEqual(cm.exception.code, "too_old")
        self.assertIsInstance(cm.exception.reply["id"], int)
        st = c.get_state("w2")
        self.assertEqual(st["health"]["pending"], 2)
        self.assertEqual(st["t"], 2.1)
        # Largest window allowed: max_reorder_window_s (5).
        self.assertEqual(self.open_main(c, "w5", reorder_window_s=5)["session"], "w5")


# ----- errors (§7) -------------------------------------------------------------------------------------
class TestErrors(ServiceTestCase):
    def test_framing_errors(self):
        s = self.server()
        c = self.client(s)
        self.assertEqual(c.lines_sent, 1)
        m = self.expect_error(c, '{"type":"hello"', "malformed_json")
        self.assertEqual(m["line"], 2)
        self.expect_error(c, "not json at all", "malformed_json")
        self.expect_error(c, '{"type":"get_state","session":"x",}', "malformed_json")
        self.expect_error(c, b'{"type":"hello","client":"\xff\xfe"}', "malformed_json")   # not UTF-8
        for raw in ("[1,2,3]", "42", '"hello"', "null", "true"):
            self.expect_error(c, raw, "not_an_object")
        self.expect_error(c, {"type": "teleport", "id": 7}, "unknown_type", rid=7)
        self.expect_error(c, {"type": "lidar", "session": "x", "t": 1.0, "id": "l"}, "unknown_type", rid="l")
        self.expect_error(c, {"id": 8}, "missing_field", rid=8)
        self.expect_error(c, {"type": 5, "id": 9}, "invalid_field", rid=9)
        self.expect_error(c, {"type": "hello", "id": "x" * 129}, "invalid_field")
        self.expect_error(c, {"type": "hello", "id": {"a": 1}}, "invalid_field")
        self.expect_error(c, {"type": "hello", "id": 10, "protocol": 1}, "invalid_field", rid=10)
        # blank lines count as lines (the error names line numbers on this connection)
        c.send_line("")
        m = self.expect_error(c, "{", "malformed_json")

    def test_unsupported_protocol(self):
        s = self.server()
        c = self.client(s, hello=False)
        self.expect_error(c, {"type": "hello", "id": 1, "protocol": "rowloc-service/2"}, "unsupported_protocol", rid=1)
        self.expect_error(c, {"type": "hello", "id": 2, "protocol": "rowloc-service/0"}, "unsupported_protocol", rid=2)
        self.assertEqual(c.hello()["protocol"], "rowloc-service/1")

    def test_line_too_long(self):
        s = self.server(config={"max_line_bytes": 4096})
        c = self.client(s)
        big = json.dumps({"type": "hello", "id": 1, "client": "x" * 10000})
        self.expect_error(c, big, "line_too_long")
        # The rest of the line is skipped, not read as a new line: the next line works.
        n = c.send_lines(['{"type":"list_sessions","client":"' + "y" * 8000 + '"}', '{"type":"hello","id":"after"}'])
        m = c.read_pushed(10)
        self.assertEqual((m["type"], m["code"], m["id"], m["line"]), ("error", "line_too_long", None, n - 1), m.raw)
        m = c.read_pushed(10)
        self.assertEqual((m["type"], m["id"]), ("hello", "after"), m.raw)
        # A line just under the limit is read.
        ok = json.dumps({"type": "hello", "id": 3, "client": "z" * 3900})
        self.assertLess(len(ok), 4096)
        self.assertEqual(c.request(json.loads(ok))["type"], "hello")
        self.assertEqual(c.stats()["rejects"].get("line_too_long"), 2)

    def test_unauthorized(self):
        token_file = os.path.join(self.workdir, "token")
        with open(token_file, "w") as f:
            f.write("s3cret-token\n")
        s = self.server(args=["--token-file", token_file, "--listen", "127.0.0.1"])
        c = self.client(s, hello=False)
        n = c.send_line('{"type":"list_sessions","id":1}')
        m = c.read_pushed(10)
        self.assertEqual((m["type"], m["code"], m["id"], m["line"]), ("error", "unauthorized", 1, n), m.raw)
        for request in ({"type": "get_state", "session": "x", "id": 2},
                        {"type": "open_session", "vehicle": VEHICLE, "map": MAP, "id": 3},
                        {"type": "imu", "session": "x", "t": 0.0, "sensor": "imu", "accel_x_mps2": 0,
                         "accel_y_mps2": 0, "gyro_z_radps": 0, "id": 4},
                        {"type": "hello", "token": "wrong", "id": 5},
                        {"type": "hello", "token": "s3cret-token-and-more", "id": 6}):
            n = c.send_line(json.dumps(request))
            m = c.read_pushed(10)
            self.assertEqual((m["type"], m.get("code"), m["id"], m.get("line")),
                             ("error", "unauthorized", request["id"], n), m.raw)
        h = c.hello(token="s3cret-token")
        self.assertEqual(h["auth"], "token")
        self.assertEqual(c.list_sessions()["sessions"], [])
        # Another connection is not authorised by the first one's hello.
        c2 = self.client(s, hello=False)
        with self.assertRaises(RowlocError) as cm:
            c2.list_sessions()
        self.assertEqual(cm.exception.code, "unauthorized")
        self.assertEqual(c2.hello(token="s3cret-token")["auth"], "token")

    def test_listen_elsewhere_needs_token(self):
        p = subprocess.Popen([ROWLOC, "serve", "--port", "0", "--listen", "0.0.0.0",
                              "--vehicles", os.path.join(SRC, "config", "vehicles"), "--maps", os.path.join(SRC, "maps"),
                              "--filters", os.path.join(SRC, "config", "filters")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            out, err = p.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            p.kill()
            out, err = p.communicate()
            self.fail("rowloc serve --listen 0.0.0.0 without --token-file kept running: " + out.decode()[:300])
        self.assertNotEqual(p.returncode, 0)
        self.assertNotIn(b'"listening"', out)
        self.assertIn(b"token", err)

    def test_field_errors(self):
        s = self.server()
        c = self.client(s)
        self.open_main(c, "f1", initial_pose=INITIAL_POSE)
        imu = '{"type":"imu","session":"f1","t":T,"sensor":"imu","accel_x_mps2":AX,"accel_y_mps2":0.0,"gyro_z_radps":0.0}'
        # missing_field
        self.expect_error(c, {"type": "get_state", "id": 1}, "missing_field", rid=1)
        self.expect_error(c, {"type": "close_session", "id": 2}, "missing_field", rid=2)
        self.expect_error(c, {"type": "subscribe", "id": 3}, "missing_field", rid=3)
        self.expect_error(c, {"type": "open_session", "map": MAP, "session": "nv", "id": 4}, "missing_field", rid=4)
        self.expect_error(c, {"type": "imu", "session": "f1", "sensor": "imu", "accel_x_mps2": 0.0, "accel_y_mps2": 0.0,
                              "gyro_z_radps": 0.0, "id": 5}, "missing_field", rid=5, session="f1")
        self.expect_error(c, {"type": "imu", "t": 1.0, "sensor": "imu", "accel_x_mps2": 0.0, "accel_y_mps2": 0.0,
                              "gyro_z_radps": 0.0, "id": 6}, "missing_field", rid=6, session="f1")
        self.expect_error(c, {"type": "wheels", "session": "f1", "t": 0.1, "id": 7,
                              "speed_radps": {"front_left": 1.0, "front_right": 1.0, "rear_left": 1.0}},
                          "missing_field", rid=7, session="f1")
        self.expect_error(c, {"type": "gps", "session": "f1", "t": 0.1, "sensor": "gnss", "fix": "sbas", "id": 8},
                          "missing_field", rid=8, session="f1")
        # invalid_field: types, non-finite numbers, out-of-range values
        self.expect_error(c, {"type": "get_state", "session": 5, "id": 10}, "invalid_field", rid=10)
        self.expect_error(c, imu.replace("T", "0.1").replace("AX", "1e999"), "invalid_field", session="f1")
        self.expect_error(c, imu.replace("T", "0.1").replace("AX", "-1e999"), "invalid_field", session="f1")
        self.expect_error(c, imu.replace("T", "1e999").replace("AX", "0.0"), "invalid_field", session="f1")
        self.expect_error(c, imu.replace("T", '"0.1"').replace("AX", "0.0"), "invalid_field", session="f1")
        self.expect_error(c, imu.replace("T", "0.1").replace("AX", "null"), "invalid_field", session="f1")
        self.expect_error(c, {"type": "gps", "session": "f1", "t": 0.1, "sensor": "gnss", "fix": "sbas", "id": 11,
                              "latitude_deg": 91.0, "longitude_deg": 7.0, "altitude_m": 240.0,
                              "sigma_horizontal_m": 0.5, "sigma_vertical_m": 1.0}, "invalid_field", rid=11, session="f1")
        self.expect_error(c, {"type": "gps", "session": "f1", "t": 0.1, "sensor": "gnss", "fix": "perfect", "id": 12,
                              "latitude_deg": 45.0, "longitude_deg": 7.0, "altitude_m": 240.0,
                              "sigma_horizontal_m": 0.5, "sigma_vertical_m": 1.0}, "invalid_field", rid=12, session="f1")
        self.expect_error(c, {"type": "ultrasonic", "session": "f1", "t": 0.1, "sensor": "us_front_left",
                              "range_m": -1.0, "id": 13}, "invalid_field", rid=13, session="f1")
        self.expect_error(c, {"type": "ultrasonic", "session": "f1", "t": 0.1, "sensor": "us_nowhere",
                              "range_m": 1.0, "id": 14}, "invalid_field", rid=14, session="f1")
        self.expect_error(c, {"type": "subscribe", "session": "f1", "stream": "video", "id": 15}, "invalid_field", rid=15)
        self.expect_error(c, {"type": "subscribe", "session": "f1", "stream": "state", "rate_hz": -1, "id": 16},
                          "invalid_field", rid=16)
        for i, extra in enumerate(({"reorder_window_s": 5.5}, {"reorder_window_s": -0.1}, {"period_s": 0},
                                   {"period_s": "fast"}, {"vehicle_config": "not an object"},
                                   {"initial_pose": dict(INITIAL_POSE, sigma_xy_m=-1.0)},
                                   {"origin": {"latitude_deg": 95.0, "longitude_deg": 7.0, "altitude_m": 0.0}})):
            req = dict({"type": "open_session", "session": f"bad{i}", "vehicle": VEHICLE, "id": 20 + i}, **extra)
            if "vehicle_config" in extra:
                del req["vehicle"]
            if "origin" not in extra:
                req["map"] = MAP
            self.expect_error(c, req, "invalid_field", rid=20 + i)
        # No failed open_session left a session behind; f1 received nothing.
        self.assertEqual([x["session"] for x in c.list_sessions()["sessions"]], ["f1"])
        self.assertEqual(c.close_session("f1")["messages"], 0)

    def test_session_errors(self):
        # A vehicles directory with a link leading out of it, and one that stays inside.
        vehicles = os.path.join(self.workdir, "vehicles")
        shutil.copytree(os.path.join(SRC, "config", "vehicles"), vehicles)
        # the filter files the vehicle files recommend ("recommended_filter": "../filters/NAME.json")
        shutil.copytree(os.path.join(SRC, "config", "filters"), os.path.join(self.workdir, "filters"))
        outside = os.path.join(self.workdir, "outside")
        os.makedirs(outside)
        shutil.copy(os.path.join(vehicles, VEHICLE + ".json"), os.path.join(outside, "escape.json"))
        os.symlink(os.path.join("..", "outside", "escape.json"), os.path.join(vehicles, "escape.json"))
        os.symlink(os.path.join(outside, "escape.json"), os.path.join(vehicles, "escape-abs.json"))
        os.symlink(VEHICLE + ".json", os.path.join(vehicles, "alias.json"))
        maps = os.path.join(self.workdir, "maps")
        shutil.copytree(os.path.join(SRC, "maps"), maps)
        with open(os.path.join(maps, "broken.geojson"), "w") as f:
            f.write('{"type": "FeatureCollection", "features": [')
        s = self.server(vehicles_dir=vehicles, maps_dir=maps)
        c = self.client(s)
        self.open_main(c, "s1")

        def open_error(code, **kw):
            req = {"type": "open_session", "id": c.new_id()}
            req.update(kw)
            m = self.expect_error(c, req, code, rid=req["id"], session="s1")
            return m

        # unknown_session: every request naming a session, and a sensor message
        for req in ({"type": "get_state", "session": "nope"}, {"type": "close_session", "session": "nope"},
                    {"type": "subscribe", "session": "nope"}, {"type": "unsubscribe", "session": "nope"},
                    {"type": "imu", "session": "nope", "t": 0.0, "sensor": "imu", "accel_x_mps2": 0.0,
                     "accel_y_mps2": 0.0, "gyro_z_radps": 0.0}):
            rid = c.new_id()
            self.expect_error(c, dict(req, id=rid), "unknown_session", rid=rid, session="s1")
        # the same without an id: the error has id null
        self.expect_error(c, {"type": "imu", "session": "nope", "t": 0.0, "sensor": "imu", "accel_x_mps2": 0.0,
                              "accel_y_mps2": 0.0, "gyro_z_radps": 0.0}, "unknown_session", session="s1")
        # session_exists
        open_error("session_exists", session="s1", vehicle=VEHICLE, map=MAP)
        # invalid_name: sessions, vehicles, maps, filters that are not plain names
        for name in ("../x", "a/b", "/etc/passwd", "..", "bad name", "x" * 65, "tab\there"):
            open_error("invalid_name", session=name, vehicle=VEHICLE, map=MAP)
        for name in ("../x", "/etc/passwd", "../vehicles/" + VEHICLE, "..", "escape", "escape-abs"):
            open_error("invalid_name", session="n1", vehicle=name, map=MAP)
        for name in ("../maps/sample-vineyard", "/etc/passwd", ".."):
            open_error("invalid_name", session="n1", vehicle=VEHICLE, map=name)
        for name in ("../filters/default", "/etc/passwd", "default/../default"):
            open_error("invalid_name", session="n1", vehicle=VEHICLE, map=MAP, filter=name)
        # a link that stays inside its directory is a name like any other
        self.assertEqual(c.open_session("alias", map=MAP, session="n-alias")["session"], "n-alias")
        self.assertEqual(c.open_session(VEHICLE, map=MAP, session="x" * 64)["session"], "x" * 64)
        # unknown_vehicle, unknown_map, unknown_filter
        open_error("unknown_vehicle", session="n2", vehicle="no-such-vehicle", map=MAP)
        open_error("unknown_map", session="n2", vehicle=VEHICLE, map="no-such-map")
        open_error("unknown_filter", session="n2", vehicle=VEHICLE, map=MAP, filter="no-such-filter")
        # invalid_config: a vehicle, filter or map that is refused; the message names the key
        with open(os.path.join(SRC, "config", "vehicles", VEHICLE + ".json")) as f:
            good_vehicle = json.load(f)
        bad_vehicle = dict(good_vehicle, kind="hovercraft")
        m = open_error("invalid_config", session="n3", vehicle_config=bad_vehicle, map=MAP)
        self.assertIn("kind", m["message"])
        no_wheels = {k: v for k, v in good_vehicle.items() if k != "wheels"}
        m = open_error("invalid_config", session="n3", vehicle_config=no_wheels, map=MAP)
        self.assertIn("wheels", m["message"])
        with open(os.path.join(SRC, "tests", "data", "filters", "bad-gate.json")) as f:
            bad_filter = json.load(f)
        m = open_error("invalid_config", session="n3", vehicle=VEHICLE, map=MAP, filter_config=bad_filter)
        self.assertIn("gate_probability", m["message"])
        open_error("invalid_config", session="n3", vehicle=VEHICLE, map="broken")
        # none of these left a session
        self.assertEqual(sorted(x["session"] for x in c.list_sessions()["sessions"]), ["n-alias", "s1", "x" * 64])
        stats = c.stats()
        for code in ("unknown_session", "session_exists", "invalid_name", "unknown_vehicle", "unknown_map",
                     "unknown_filter", "invalid_config"):
            self.assertGreater(stats["rejects"].get(code, 0), 0, code)

    def test_rejected(self):
        path = os.path.join(SRC, "tests", "data", "logs", "agrimaro-tiles-out-of-range.ndjson")
        header, lines = read_log(path)
        bad = next(i for i, x in enumerate(lines) if '"left_front":500' in x.replace(" ", ""))
        s = self.server()
        c = self.client(s)
        # Without a window the filter sees the message at once: the error names its id.
        c.open_session("agrimaro-swerve", header=header, session="r0", reorder_window_s=0)
        stream_log(c, "r0", lines[:bad])
        with self.assertRaises(RowlocError) as cm:
            c.send("r0", json.loads(lines[bad]), ack=True)
        self.assertEqual(cm.exception.code, "rejected")
        self.assertIn("speed_radps", cm.exception.message)
        self.assertAlive(c, "r0")
        stream_log(c, "r0", lines[bad + 1:])
        st = c.get_state("r0")
        self.assertEqual(st["health"]["rejected_messages"], 1)
        # With the default window the refusal comes when the message leaves the window (the log
        # goes on with the messages of agrimaro-tiles-head.ndjson after its 19th).
        _, more = read_log(os.path.join(SRC, "tests", "data", "logs", "agrimaro-tiles-head.ndjson"))
        self.assertEqual(more[:bad], lines[:bad])
        c.open_session("agrimaro-swerve", header=header, session="r1")
        r = stream_log(c, "r1", lines + more[len(lines):], strict=False)
        self.assertEqual([e["code"] for e in r["errors"]], ["rejected"], [e.raw for e in r["errors"]])
        self.assertIn("speed_radps", r["errors"][0]["message"])
        self.assertEqual(c.get_state("r1")["health"]["rejected_messages"], 1)
        c.close_session("r1")
        self.assertGreater(c.stats()["rejects"].get("rejected", 0), 1)

    def test_limit_exceeded(self):
        s = self.server(config={"max_sessions": 3, "max_connections": 3, "max_inline_config_bytes": 2048,
                                "max_journal_bytes": 60000})
        c = self.client(s)
        for i in range(3):
            self.open_main(c, f"L{i}", initial_pose=INITIAL_POSE)
        self.expect_error(c, {"type": "open_session", "id": 1, "session": "L3", "vehicle": VEHICLE, "map": MAP},
                          "limit_exceeded", rid=1)
        c.close_session("L2")
        self.open_main(c, "L3", initial_pose=INITIAL_POSE)
        c.close_session("L3")
        # inline configuration above max_inline_config_bytes
        with open(os.path.join(SRC, "config", "vehicles", VEHICLE + ".json")) as f:
            vehicle = json.load(f)
        big = dict(vehicle, padding="p" * 4000)
        self.expect_error(c, {"type": "open_session", "id": 2, "session": "big", "vehicle_config": big, "map": MAP},
                          "limit_exceeded", rid=2)
        small = c.open_session(vehicle_config=vehicle, map=MAP, session="small")   # the same without padding
        c.close_session(small["session"])
        # a journal that reaches max_journal_bytes refuses further messages of its session
        r = stream_log(c, "L0", LOG["short"]["lines"], strict=False)
        codes = {e["code"] for e in r["errors"]}
        self.assertEqual(codes, {"limit_exceeded"})
        refused = len(r["errors"])
        self.assertGreater(refused, 100)
        self.assertLess(os.path.getsize(os.path.join(s.journal_dir, "L0.ndjson")), 60000 + 1)
        self.assertAlive(c, "L0")
        listed = {x["session"]: x for x in c.list_sessions()["sessions"]}
        self.assertEqual(listed["L0"]["messages"], SHORT_MESSAGES - refused)
        # connections above max_connections are told limit_exceeded and closed
        c2 = self.client(s)
        c3 = self.client(s)
        c4 = s.connect(timeout=10)
        self._clients.append(c4)
        m = c4.read_pushed(10)
        self.assertIsNotNone(m)
        self.assertEqual((m["type"], m["code"]), ("error", "limit_exceeded"), m.raw)
        with self.assertRaises(ConnectionError):
            c4.read_pushed(10)
        self.assertAlive(c2)
        c3.close()
        deadline = time.monotonic() + 10
        while True:   # the server notices the closed connection
            c5 = s.connect(timeout=10)
            try:
                self.assertEqual(c5.hello()["type"], "hello")
                break
            except (RowlocError, ConnectionError):
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
            finally:
                c5.close()
        self.assertGreaterEqual(c.stats()["rejects"].get("limit_exceeded", 0), 3)


# ----- the journal: resume after kill -9, replay ------------------------------------------------------
class TestJournal(ServiceTestCase):
    def test_kill9_and_resume(self):
        lines = LOG["main"]["lines"]
        half = 6000                      # t = 24.5 s: initialised
        s1 = self.server()
        c = self.client(s1)
        self.open_main(c, "res1")
        stream_log(c, "res1", lines[:half])
        before = c.get_state("res1")
        self.check_state(before, "res1")
        # a second session with everything inline, an initial pose and its own window and period
        with open(os.path.join(SRC, "config", "vehicles", VEHICLE + ".json")) as f:
            vehicle_config = json.load(f)
        # canopy-gnss-flat.json extends canopy-gnss.json: inline goes what it loads to (as `rowloc send`)
        filter_config = json.loads(subprocess.run(
            [ROWLOC, "config", "show", "--filter", os.path.join(SRC, "config", "filters", "canopy-gnss-flat.json")],
            check=True, capture_output=True, text=True).stdout)
        c.open_session(vehicle_config=vehicle_config, filter_config=filter_config, header=LOG["main"]["header"],
                       initial_pose=INITIAL_POSE, reorder_window_s=0.5, period_s=0.25, session="res2")
        stream_log(c, "res2", lines[:half // 2])
        before2 = c.get_state("res2")
        s1.kill9()
        c.close()
        s2 = self.server(journal_dir=s1.journal_dir)
        c = self.client(s2)
        listed = {x["session"]: x for x in c.list_sessions()["sessions"]}
        self.assertIn("res1", listed)
        self.assertEqual(listed["res1"]["messages"], half)
        after = c.get_state("res1")
        self.assertEqual(without(after, "id"), without(before, "id"))
        self.assertEqual(without(c.get_state("res2"), "id"), without(before2, "id"))
        stream_log(c, "res2", lines[half // 2:half])
        c.open_session(vehicle_config=vehicle_config, filter_config=filter_config, header=LOG["main"]["header"],
                       initial_pose=INITIAL_POSE, reorder_window_s=0.5, period_s=0.25, session="ref2")
        stream_log(c, "ref2", lines[:half])
        self.assertEqual(without(c.get_state("res2"), "id", "session"), without(c.get_state("ref2"), "id", "session"))
        # and it goes on as if nothing had happened
        stream_log(c, "res1", lines[half:])
        resumed = c.get_state("res1")
        self.open_main(c, "ref")
        stream_log(c, "ref", lines)
        reference = c.get_state("ref")
        self.assertEqual(without(resumed, "id", "session"), without(reference, "id", "session"))
        self.assertEqual(c.close_session("res1")["messages"], MAIN_MESSAGES)

    def test_shutting_down(self):
        """After SIGTERM, requests get `shutting_down` (or the connection closes) and the server exits."""
        s = self.server()
        c = self.client(s)
        s.terminate()
        seen = []
        with self.assertRaises(ConnectionError):
            for i in range(1000):
                c.send_line(json.dumps({"type": "list_sessions", "id": 1000 + i}))
                m = c.read_pushed(5)
                self.assertIsNotNone(m)
                seen.append(m.get("code") or m["type"])
                time.sleep(0.01)
        self.assertLessEqual(set(seen), {"sessions", "shutdown", "shutting_down"}, seen)
        s.proc.wait(10)
        self.assertEqual(s.proc.returncode, 0)

    def test_sessions_end_at_shutdown(self):
        """§3: a session lives until close_session, the server's shutdown or its idle timeout; §8:
        only sessions that were not closed (a crash, kill -9, a power cut) resume."""
        s1 = self.server()
        c = self.client(s1)
        self.open_main(c, "brief")
        c.close()
        self.assertIsNone(s1.stop())
        s2 = self.server(journal_dir=s1.journal_dir)
        self.assertEqual(self.client(s2).list_sessions()["sessions"], [])

    def test_replay_of_journal_gives_the_estimate_stream(self):
        s = self.server(config={"max_queue_lines": 1000000})
        c = self.client(s)
        watcher = self.client(s)
        self.open_main(c, "rep1")
        watcher.subscribe("rep1", stream="estimates")
        stream_log(c, "rep1", LOG["main"]["lines"])
        closed = c.close_session("rep1")
        self.assertEqual(closed["messages"], MAIN_MESSAGES)
        watcher.list_sessions()
        pushed = watcher.pushed(timeout=1.0)
        self.assertGreater(len(pushed), 1000)
        suffix = ',"session":"rep1"}'
        streamed = []
        for m in pushed:
            self.assertTrue(m.raw.endswith(suffix), m.raw[-100:])
            self.assertNotIn("dropped", m)
            streamed.append(m.raw[: -len(suffix)] + "}")
        journal = closed["journal"]
        self.assertTrue(os.path.isfile(journal), journal)
        self.assertIsInstance(closed["journal"], str)
        self.assertTrue(os.path.basename(closed["journal"]).startswith("rep1"), closed["journal"])
        with open(journal, encoding="utf-8") as f:
            jlines = f.read().splitlines()
        header = json.loads(jlines[0])
        self.assertEqual(header["type"], "log_header")
        self.assertEqual(header["source"], "rowloc serve")
        self.assertEqual(header["wheels"], LOG["main"]["header"]["wheels"])
        self.assertEqual(header["ultrasonic"], LOG["main"]["header"]["ultrasonic"])
        self.assertEqual(header["origin"], LOG["main"]["header"]["origin"])
        self.assertEqual(header["reorder_window_s"], WINDOW)
        self.assertEqual(len(jlines), 1 + MAIN_MESSAGES)
        session_json = journal[: -len(".ndjson")] + ".session.json"
        with open(session_json) as f:
            meta = json.load(f)
        self.assertIn("vehicle", meta)
        out = os.path.join(self.workdir, "replayed.ndjson")
        r = subprocess.run([ROWLOC, "replay", journal, "--vehicle", os.path.join(SRC, "config", "vehicles", VEHICLE + ".json"),
                            "--map", os.path.join(SRC, "maps", MAP + ".geojson"), "-o", out],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=120)
        self.assertEqual(r.returncode, 0, r.stdout.decode(errors="replace")[-2000:])
        with open(out, encoding="utf-8") as f:
            replayed = f.read().splitlines()
        first_diff = next((i for i, (a, b) in enumerate(zip(streamed, replayed)) if a != b), None)
        self.assertIsNone(first_diff, None if first_diff is None else
                          f"line {first_diff + 1}:\n stream: {streamed[first_diff][:300]}\n replay: {replayed[first_diff][:300]}")
        self.assertEqual(len(streamed), len(replayed))


# ----- slow clients ------------------------------------------------------------------------------------
def slow_connection(server):
    """A connection with a tiny receive buffer that subscribes and then never reads."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.settimeout(20)
    sock.connect(("127.0.0.1", server.port))
    return RowlocClient(sock, timeout=20)


class TestSlowClient(ServiceTestCase):
    def flood(self):
        """A client subscribed to a session's states that never reads, while another connection
        streams the main log into the session (about 10000 state lines). Returns the slow client
        and the lines it then reads up to the reply to a request it sends."""
        s = self.server(config={"max_queue_lines": 64})
        feeder = self.client(s)
        slow = slow_connection(s)
        self._clients.append(slow)
        slow.hello()
        self.open_main(feeder, "busy", initial_pose=INITIAL_POSE)
        slow.subscribe("busy", "state")
        stream_log(feeder, "busy", LOG["main"]["lines"])
        feeder.get_state("busy")
        stats = feeder.stats()
        self.assertGreater(stats["dropped_states"], 1000, stats)
        # The slow connection's queue never held more than its bound (64 pushed lines plus the
        # replies it has not read), although about 10000 lines were pushed to it. (Not the
        # process's resident size: under AddressSanitizer that grows by hundreds of MiB from the
        # allocator's quarantine alone, and 10000 state lines would be only ~10 MiB anyway.)
        self.assertLessEqual(stats["queue_high_water_lines"], 2 * 64, stats)
        # The slow client is still connected, and a reply to a request is never dropped.
        reply_id = slow.new_id()
        slow.send_line(json.dumps({"type": "list_sessions", "id": reply_id}))
        lines = []
        while True:
            m = slow.read_pushed(10)
            self.assertIsNotNone(m, "no reply from the server")
            if m.get("id") == reply_id:
                self.assertEqual(m["type"], "sessions")
                break
            lines.append(m)
        self.assertLess(len(lines), 6000)      # far fewer than were pushed
        self.assertEqual(slow.get_state("busy")["session"], "busy")
        return lines

    def test_drop_oldest_bounds_memory(self):
        lines = self.flood()
        times = [m["t"] for m in lines if m.get("type") == "state"]
        self.assertEqual(times, sorted(times))
        self.assertEqual(lines[-1]["t"], times[-1])

    def test_drop_oldest_tells_the_client(self):
        """§5: the dropped lines are counted in a `dropped` count in the next pushed line."""
        lines = self.flood()
        self.assertTrue(any(isinstance(m.get("dropped"), int) and m["dropped"] > 0 for m in lines),
                        [m.raw[:120] for m in lines[:3]])

    def test_disconnect_policy(self):
        s = self.server(config={"max_queue_lines": 32, "slow_client": "disconnect"})
        feeder = self.client(s)
        slow = slow_connection(s)
        self._clients.append(slow)
        slow.hello()
        self.open_main(feeder, "busy", initial_pose=INITIAL_POSE)
        slow.subscribe("busy", "state")
        stream_log(feeder, "busy", LOG["main"]["lines"][:5000])
        feeder.get_state("busy")
        with self.assertRaises(ConnectionError):
            for _ in range(100000):
                if slow.read_pushed(10) is None:
                    self.fail("the slow connection was not closed")
        # the session and the other connection are unaffected
        self.assertEqual(feeder.get_state("busy")["session"], "busy")
        self.assertConnections(feeder, 1)


class TestTimeouts(ServiceTestCase):
    def test_idle_connection_is_closed(self):
        s = self.server(config={"connection_idle_timeout_s": 1})
        c = self.client(s)
        busy = self.client(s)
        deadline = time.monotonic() + 8
        with self.assertRaises(ConnectionError):
            while time.monotonic() < deadline:
                c.read_pushed(0.5)
                busy.hello()          # a connection that sends stays open
        self.assertLess(time.monotonic(), deadline, "the idle connection was not closed")
        self.assertConnections(busy, 1)

    def test_idle_session_is_closed(self):
        s = self.server(config={"session_idle_timeout_s": 1})
        with s.connect() as c:
            c.hello()
            self.open_main(c, "idle")
        c = self.client(s)
        deadline = time.monotonic() + 8
        while c.list_sessions()["sessions"] and time.monotonic() < deadline:
            time.sleep(0.25)
        self.assertEqual(c.list_sessions()["sessions"], [])
        self.assertGreater(time.monotonic() + 8 - deadline, 0.9)


class TestClientFraming(unittest.TestCase):
    """The client's own framing, against a fake server (no rowloc needed)."""

    def _pair(self, **kw):
        a, b = socket.socketpair()
        self.addCleanup(a.close)
        self.addCleanup(b.close)
        return RowlocClient(a, timeout=2, **kw), b

    def test_reply_matching_and_queue(self):
        client, server = self._pair()

        def serve():
            f = server.makefile("rb")
            req = json.loads(f.readline())
            server.sendall(b'{"type":"state","session":"s"}\n\n{"type":"error","id":null,"code":"malformed_json",'
                           b'"message":"x","line":9}\n')
            server.sendall(('{"type":"hello","id":%d,"protocol":"rowloc-service/1"}\n' % req["id"]).encode())
            req = json.loads(f.readline())
            server.sendall(('{"type":"error","id":%d,"code":"unknown_session","message":"no","line":2}\n'
                            % req["id"]).encode())
            f.readline()
            server.sendall(b'{"type":"error","id":null,"code":"line_too_long","message":"long","line":3}\n')

        t = threading.Thread(target=serve)
        t.start()
        self.assertEqual(client.hello()["type"], "hello")
        with self.assertRaises(RowlocError) as cm:
            client.get_state("s")
        self.assertEqual(cm.exception.code, "unknown_session")
        self.assertEqual(cm.exception.line, 2)
        with self.assertRaises(RowlocError) as cm:          # an error naming our line, id unreadable
            client.request({"type": "hello"})
        self.assertEqual(cm.exception.code, "line_too_long")
        t.join()
        pushed = client.pushed()
        self.assertEqual([m["type"] for m in pushed], ["state", "error"])
        self.assertEqual(pushed[0].raw, '{"type":"state","session":"s"}')
        self.assertIsInstance(pushed[0], Message)
        self.assertIsNone(client.read_pushed(0.05))

    def test_limits_and_eof(self):
        client, server = self._pair(max_line_bytes=100)
        server.sendall(b'{"type":"state","pad":"' + b"x" * 200 + b'"}\n')
        with self.assertRaises(ProtocolError):
            client.read_pushed(1)
        client, server = self._pair()
        server.sendall(b'[1]\n')
        with self.assertRaises(ProtocolError):
            client.read_pushed(1)
        client, server = self._pair()
        server.sendall(b'{"type":"state"}\n')
        server.close()
        self.assertEqual(client.read_pushed(1)["type"], "state")
        with self.assertRaises(ConnectionError):
            client.read_pushed(1)

    def test_encoding(self):
        client, server = self._pair()
        with self.assertRaises(ValueError):
            client.send("s", {"type": "imu", "t": float("nan")})
        client.send("s", {"type": "imu", "t": 1.5})
        self.assertEqual(json.loads(server.recv(1000)), {"type": "imu", "t": 1.5, "session": "s"})
        self.assertEqual(add_session_key('{"type":"imu","t":0.1}', "a"), '{"session":"a","type":"imu","t":0.1}')
        self.assertEqual(add_session_key('{"type":"imu"}', "a", 3), '{"session":"a","id":3,"type":"imu"}')


if __name__ == "__main__":
    unittest.main()
