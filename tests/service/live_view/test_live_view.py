"""Tests of the live view of `rowloc serve` (docs/live-view.md) against real processes.

HttpEndpointTest: the HTTP/WebSocket endpoint with plain clients (http.client, minimal_websocket):
the page, 404/405, the token rule, the stream of states, a client that never reads.
BrowserTest: headless Chromium (Debian's `chromium`, scripts/setup) loads the page while a drive
streams; the test reads what the page shows through the DevTools protocol (Runtime.evaluate) and
compares it with the session's `get_state` over the socket API, saves a screenshot, and checks that
the page reconnects when the service restarts. No timing thresholds: every wait is a poll with a
generous deadline that only fails a test that would otherwise hang.

Environment: ROWLOC_BIN, ROWLOC_SOURCE_DIR, PYTHONPATH with service/python; CHROMIUM (default
`chromium`); LIVE_VIEW_SCREENSHOT: where to save the screenshot (CTest: the build tree; the picture in
the docs is taken by hand from scripts/demo, docs/live-view.md).

The drive is simulated from config/scenarios/vineyard-002-4us.json and its world's true row map
(the simulator's row-map.geojson) is the map the sessions get, as MAP from a maps directory of its
own: the vehicle drives in the lanes of the rows it sees and the echoes meet them.
"""

import base64
import http.client
import json
import os
import select
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import unittest
import urllib.parse

from minimal_websocket import HandshakeRefused, WebSocket
from rowloc_client import RowlocClient, read_log, stream_log

ROWLOC = os.environ.get("ROWLOC_BIN")
SRC = os.environ.get("ROWLOC_SOURCE_DIR")
CHROMIUM = os.environ.get("CHROMIUM", "chromium")
SCREENSHOT = os.environ.get("LIVE_VIEW_SCREENSHOT")
SCENARIO = "vineyard-002-4us"       # config/scenarios: five lanes of the world vineyard-002
VEHICLE, MAP = "vineyard-ugv-4ws", "vineyard-002"  # the scenario's vehicle; its world's true row map
ROWS = 6                  # the rows of MAP (config/worlds/vineyard-002.json)
INITIALISED_AFTER = 6000  # the filter initialises from GNSS at message 4069 (t = 16.6 s)
DEADLINE_S = 120          # a wait that has not ended by then is a hang

_TMP = None
HEADER, LINES = None, None
MAPS = None  # the maps directory of the servers: MAP only


def setUpModule():
    global _TMP, HEADER, LINES, MAPS
    if not ROWLOC or not SRC:
        raise unittest.SkipTest("set ROWLOC_BIN and ROWLOC_SOURCE_DIR")
    _TMP = tempfile.mkdtemp(prefix="rowloc-live-view-")
    run = os.path.join(_TMP, "sim")
    r = subprocess.run([ROWLOC, "simulate", os.path.join(SRC, "config", "scenarios", SCENARIO + ".json"),
                        "-o", run, "--no-baselines"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=600)
    if r.returncode != 0:
        raise RuntimeError("rowloc simulate failed:\n" + r.stdout.decode(errors="replace")[-3000:])
    HEADER, LINES = read_log(os.path.join(run, "sensors.ndjson"))
    LINES = LINES[:20000]
    MAPS = os.path.join(_TMP, "maps")
    os.mkdir(MAPS)
    shutil.copyfile(os.path.join(run, "row-map.geojson"), os.path.join(MAPS, MAP + ".geojson"))


def tearDownModule():
    if _TMP:
        shutil.rmtree(_TMP, ignore_errors=True)


def wait_until(condition, what, deadline_s=DEADLINE_S):
    """Polls condition() (a value, falsy while not there) until it is truthy; fails after deadline_s."""
    end = time.monotonic() + deadline_s
    last = None
    while time.monotonic() < end:
        last = condition()
        if last:
            return last
        time.sleep(0.1)
    raise AssertionError(f"timed out after {deadline_s} s waiting for {what} (last: {last!r})")


class Server:
    """`rowloc serve --port 0 --http-port PORT` with the shipped vehicles and filters and the drive's map."""

    def __init__(self, http_port=0, extra=()):
        self.proc = subprocess.Popen(
            [ROWLOC, "serve", "--port", "0", "--http-port", str(http_port),
             "--vehicles", os.path.join(SRC, "config", "vehicles"), "--maps", MAPS,
             "--filters", os.path.join(SRC, "config", "filters"), *extra],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        ready, _, _ = select.select([self.proc.stdout], [], [], DEADLINE_S)
        line = self.proc.stdout.readline() if ready else b""
        if not line:
            self.stop()
            raise RuntimeError("rowloc serve did not print its listening line")
        listening = json.loads(line)
        host, port = listening["tcp"].rsplit(":", 1)
        self.tcp = (host, int(port))
        self.url = listening["http"]
        parts = urllib.parse.urlsplit(self.url)
        self.http = (parts.hostname, parts.port)

    def client(self):
        return RowlocClient.connect(*self.tcp, timeout=DEADLINE_S)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc.stdout.close()
        return self.proc.returncode


def open_drive(client, session):
    client.open_session(VEHICLE, map=MAP, header=HEADER, session=session)


def http_get(server, path, headers=None, method="GET"):
    connection = http.client.HTTPConnection(*server.http, timeout=DEADLINE_S)
    connection.request(method, path, headers=headers or {})
    response = connection.getresponse()
    body = response.read()
    connection.close()
    return response.status, response.getheader("Content-Type"), body


def frame_lines(ws):
    frame = ws.recv_json()
    assert frame["type"] == "frame", frame
    return frame["lines"]


class HttpEndpointTest(unittest.TestCase):
    def setUp(self):
        self.server = Server()
        self.addCleanup(self.server.stop)

    def test_serves_the_page_and_refuses_unknown_paths(self):
        status, kind, body = http_get(self.server, "/")
        self.assertEqual(status, 200)
        self.assertTrue(kind.startswith("text/html"))
        self.assertIn(b"live-view.js", body)
        status, kind, body = http_get(self.server, "/live-view.js")
        self.assertEqual((status, kind.split(";")[0]), (200, "text/javascript"))
        self.assertIn(b"new WebSocket", body)
        self.assertEqual(http_get(self.server, "/live-view.css")[0], 200)
        self.assertEqual(http_get(self.server, "/nope")[0], 404)
        self.assertEqual(http_get(self.server, "/../etc/passwd")[0], 404)
        self.assertEqual(http_get(self.server, "/", method="POST")[0], 405)
        with self.assertRaises(HandshakeRefused) as refused:
            WebSocket(self.server.url.replace("http", "ws") + "other")
        self.assertEqual(refused.exception.status, 404)
        with self.assertRaises(HandshakeRefused) as foreign:  # another site's page in the user's browser
            WebSocket(self.server.url.replace("http", "ws") + "ws", headers={"Origin": "http://evil.example"})
        self.assertEqual(foreign.exception.status, 403)

    def test_the_socket_api_still_works_and_is_off_by_default(self):
        with self.server.client() as c:
            self.assertEqual(c.hello()["protocol"], "rowloc-service/1")
        plain = subprocess.Popen([ROWLOC, "serve", "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        try:
            self.assertIsNone(json.loads(plain.stdout.readline())["http"])
        finally:
            plain.send_signal(signal.SIGTERM)
            self.assertEqual(plain.wait(timeout=DEADLINE_S), 0)
            plain.stdout.close()

    def test_websocket_streams_the_watched_session(self):
        with self.server.client() as c:
            open_drive(c, "drive")
            ws = WebSocket(self.server.url.replace("http", "ws") + "ws")
            self.addCleanup(ws.close)
            # The session list comes unasked, once a second.
            wait_until(lambda: any(l["type"] == "sessions" and [s["session"] for s in l["sessions"]] == ["drive"]
                                   for l in frame_lines(ws)), "the session list")
            ws.send_json({"type": "watch", "session": "drive"})
            stream_log(c, "drive", LINES, count=INITIALISED_AFTER)
            expected = c.get_state("drive")
            self.assertTrue(expected["initialised"])
            seen = {"scene": [], "gnss": [], "echo": [], "subscribed": []}

            def final_state_seen():
                for line in frame_lines(ws):
                    if line["type"] in seen:
                        seen[line["type"]].append(line)
                    if line["type"] == "state" and line["t"] == expected["t"]:
                        return line
                return None
            state = wait_until(final_state_seen, "the session's last state")
        for key in ("session", "x_m", "y_m", "phi_rad", "covariance_xy_phi", "ellipse_2sigma", "velocity", "slip"):
            self.assertEqual(state[key], expected[key], key)
        self.assertEqual(seen["subscribed"][0]["stream"], "live")
        scene = seen["scene"][0]
        self.assertEqual((scene["session"], scene["map"], scene["vehicle"]["name"]), ("drive", MAP, VEHICLE))
        self.assertEqual(len(scene["rows"]), ROWS)  # the rows of the world the drive was simulated in
        self.assertEqual(len(scene["vehicle"]["ultrasonic"]), 4)
        self.assertTrue(seen["gnss"], "no GNSS fix reached the client")
        for fix in seen["gnss"]:
            self.assertGreater(fix["sigma_m"], 0)
            self.assertIn(fix["accepted"], (True, False, None))
        self.assertTrue(seen["echo"], "no echo reached the client")
        for echo in seen["echo"]:
            dx, dy = echo["to"][0] - echo["from"][0], echo["to"][1] - echo["from"][1]
            self.assertAlmostEqual((dx * dx + dy * dy) ** 0.5, echo["range_m"], places=9)

    def test_unknown_session_and_bad_requests_are_errors(self):
        ws = WebSocket(self.server.url.replace("http", "ws") + "ws")
        self.addCleanup(ws.close)
        ws.send_json({"type": "watch", "session": "nobody"})
        ws.send_text("not json")
        errors = []
        wait_until(lambda: errors.extend(l for l in frame_lines(ws) if l["type"] == "error") or len(errors) >= 2,
                   "two errors")
        self.assertEqual([e["code"] for e in errors[:2]], ["unknown_session", "invalid_request"])

    def test_a_client_that_never_reads_does_not_stall_the_session(self):
        with self.server.client() as c:
            open_drive(c, "drive")
            slow = WebSocket(self.server.url.replace("http", "ws") + "ws", rcvbuf=4096)
            self.addCleanup(slow.close)
            slow.send_json({"type": "watch", "session": "drive"})  # then never reads
            result = stream_log(c, "drive", LINES)  # returns once the server took every line
            self.assertEqual(result["sent"], len(LINES))
            expected = c.get_state("drive")
            # Another client still gets the newest state.
            ws = WebSocket(self.server.url.replace("http", "ws") + "ws")
            self.addCleanup(ws.close)
            ws.send_json({"type": "watch", "session": "drive"})
            wait_until(lambda: any(l["type"] == "state" and l["t"] == expected["t"] for l in frame_lines(ws)),
                       "the newest state on a second client")
            self.assertGreater(expected["t"], 70.0)  # the whole drive was applied


class HttpTokenTest(unittest.TestCase):
    def test_with_a_token_every_request_needs_it(self):
        token_file = os.path.join(_TMP, "token")
        with open(token_file, "w") as f:
            f.write("s3cret-t0ken\n")
        server = Server(extra=("--token-file", token_file))
        self.addCleanup(server.stop)
        self.assertEqual(http_get(server, "/")[0], 401)
        self.assertEqual(http_get(server, "/?token=wrong")[0], 401)
        self.assertEqual(http_get(server, "/?token=s3cret-t0ken")[0], 200)
        self.assertEqual(http_get(server, "/live-view.js", {"Authorization": "Bearer s3cret-t0ken"})[0], 200)
        base = server.url.replace("http", "ws") + "ws"
        for url in (base, base + "?token=s3cret-t0keN"):
            with self.assertRaises(HandshakeRefused) as refused:
                WebSocket(url)
            self.assertEqual(refused.exception.status, 401)
        ws = WebSocket(base + "?token=s3cret-t0ken")
        self.addCleanup(ws.close)
        self.assertEqual(frame_lines(ws)[0]["type"], "sessions")

    def test_other_addresses_need_a_token(self):
        r = subprocess.run([ROWLOC, "serve", "--listen", "0.0.0.0", "--port", "0", "--http-port", "0"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=DEADLINE_S)
        self.assertEqual(r.returncode, 2)
        self.assertIn(b"token", r.stderr)


class Chromium:
    """Headless Chromium showing `url`, driven through the DevTools protocol."""

    def __init__(self, url, width=1280, height=800):
        self.profile = tempfile.mkdtemp(prefix="rowloc-chromium-")
        try:
            self.proc = subprocess.Popen(
                [CHROMIUM, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run", "--hide-scrollbars",
                 "--remote-debugging-port=0", f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
                 url], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        except FileNotFoundError:
            raise AssertionError(f"{CHROMIUM} not found: scripts/setup installs Debian's chromium")
        endpoint = None
        end = time.monotonic() + DEADLINE_S
        while endpoint is None and time.monotonic() < end:
            ready, _, _ = select.select([self.proc.stderr], [], [], 1.0)
            if ready:
                line = self.proc.stderr.readline().decode(errors="replace")
                if not line and self.proc.poll() is not None:
                    break
                if "DevTools listening on " in line:
                    endpoint = line.split("DevTools listening on ", 1)[1].strip()
        if endpoint is None:
            self.close()
            raise AssertionError("chromium did not open its DevTools endpoint")
        threading.Thread(target=self.proc.stderr.read, daemon=True).start()  # keep its stderr drained
        port = urllib.parse.urlsplit(endpoint).port
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=DEADLINE_S)
        connection.request("GET", "/json/list")
        pages = [t for t in json.loads(connection.getresponse().read()) if t["type"] == "page"]
        connection.close()
        self.ws = WebSocket(pages[0]["webSocketDebuggerUrl"], timeout=DEADLINE_S)
        self.next_id = 0

    def call(self, method, params=None):
        self.next_id += 1
        self.ws.send_json({"id": self.next_id, "method": method, "params": params or {}})
        while True:
            reply = self.ws.recv_json()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise AssertionError(f"DevTools {method}: {reply['error']}")
                return reply["result"]

    def evaluate(self, expression):
        return self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True})["result"].get("value")

    def shown(self):
        """The texts of the page's panel elements by id ({} while the page is not loaded)."""
        return self.evaluate("""Object.fromEntries(['status', 'session', 't', 'x', 'y', 'phi', 'initialised',
            'rows-drawn', 'gnss-total', 'echoes-total', 'trail-drawn', 'frames']
            .map((id) => [id, document.getElementById(id).textContent]))""") or {}

    def screenshot(self, path):
        data = base64.b64decode(self.call("Page.captureScreenshot", {"format": "png"})["data"])
        with open(path, "wb") as f:
            f.write(data)
        return data

    def close(self):
        if getattr(self, "ws", None):
            self.ws.close()
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


class BrowserTest(unittest.TestCase):
    def test_page_shows_the_session_state_while_a_drive_streams(self):
        server = Server()
        self.addCleanup(server.stop)
        with server.client() as c:
            open_drive(c, "vineyard-drive")
            open_drive(c, "other-drive")  # a second session the page can pick
            stream_log(c, "vineyard-drive", LINES, count=INITIALISED_AFTER)
            browser = Chromium(server.url + "?session=vineyard-drive&scale=18")
            self.addCleanup(browser.close)
            wait_until(lambda: browser.shown().get("status") == "live", "the page to connect")
            # The drive goes on while the page watches (5 times real time: fixes and echoes arrive live).
            stream_log(c, "vineyard-drive", LINES, rate=5.0, start=INITIALISED_AFTER, count=4000)
            expected = c.get_state("vineyard-drive")
            # The drive belongs to the map: the vehicle is in a lane and the map-aided update uses the echoes.
            self.assertGreater(expected["health"]["sensors"]["ultrasonic"]["accepted"], 0)
            shown = wait_until(lambda: (lambda s: s if s.get("t") == f"{expected['t']:.3f}" else None)(browser.shown()),
                               "the page to show the session's state")
            self.assertEqual(shown["session"], "vineyard-drive")
            self.assertEqual(shown["initialised"], "initialised")
            for key, value, digits in (("x", expected["x_m"], 3), ("y", expected["y_m"], 3),
                                       ("phi", expected["phi_rad"], 4)):
                self.assertEqual(shown[key], f"{value:.{digits}f}", key)
            self.assertEqual(shown["rows-drawn"], str(ROWS))
            self.assertGreater(int(shown["gnss-total"]), 0)
            self.assertGreater(int(shown["echoes-total"]), 0)
            self.assertGreater(int(shown["trail-drawn"]), 10)
            options = browser.evaluate("Array.from(document.getElementById('session-select').options)"
                                       ".map((o) => o.value).filter((v) => v)")
            self.assertEqual(options, ["other-drive", "vineyard-drive"])
            png = browser.screenshot(os.path.join(_TMP, "live-view.png"))
            self.assertEqual(png[:8], b"\x89PNG\r\n\x1a\n")
            if SCREENSHOT:
                shutil.copyfile(os.path.join(_TMP, "live-view.png"), SCREENSHOT)

    def test_page_reconnects_when_the_service_restarts(self):
        first = Server()
        http_port = first.http[1]
        with first.client() as c:
            open_drive(c, "drive")
            stream_log(c, "drive", LINES, count=INITIALISED_AFTER)
        browser = Chromium(first.url + "?session=drive")
        self.addCleanup(browser.close)
        wait_until(lambda: browser.shown().get("initialised") == "initialised", "the first server's state")
        self.assertEqual(first.stop(), 0)
        wait_until(lambda: browser.shown().get("status", "").startswith("disconnected"), "the page to see the stop")
        second = Server(http_port=http_port)  # same page address
        self.addCleanup(second.stop)
        with second.client() as c:
            open_drive(c, "drive")
            stream_log(c, "drive", LINES, count=INITIALISED_AFTER + 500)
            expected = c.get_state("drive")
        shown = wait_until(lambda: (lambda s: s if s.get("t") == f"{expected['t']:.3f}" else None)(browser.shown()),
                           "the page to show the restarted service's state")
        self.assertEqual(shown["status"], "live")
        self.assertEqual(shown["x"], f"{expected['x_m']:.3f}")


if __name__ == "__main__":
    unittest.main()
