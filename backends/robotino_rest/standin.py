"""A local stand-in for a Robotino 4's REST API (tests, demos).

Serves the documented endpoints on 127.0.0.1 (ephemeral port by default)
and simulates the base: ``/data/omnidrive`` sets a body velocity that is
integrated into the odometry and dropped to zero ("the robot stops") when
no new command arrives within ``timeout`` (0.2 s, as the wiki says).
``stops`` counts those timeouts; ``commands`` logs (time, [vx, vy, omega]).

    with RestStandIn() as robot:
        backend = open_backend("robotino_rest", base_url=robot.url)
"""
from __future__ import annotations

import json
import math
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np

from rll_bt.clock import Clock, WallClock


class RestStandIn:
    def __init__(self, *, timeout: float = 0.2, clock: Clock | None = None, port: int = 0,
                 scan_points: int = 360, image_size: tuple[int, int] = (320, 240)):
        self.clock = clock or WallClock()
        self.timeout = timeout
        self.lock = threading.Lock()
        self.pose = [0.0, 0.0, 0.0]
        self.velocity = (0.0, 0.0, 0.0)
        self.bumper = False
        self.distances = [0.25] * 9
        self.scan_ranges = np.full(scan_points, 2.0)
        self.image_size = image_size
        self.commands: list[tuple[float, list[float]]] = []
        self.requests: list[tuple[str, str]] = []
        self.stops = 0
        self.seq = 0
        self._last_command = -math.inf
        self._t = self.clock.now()
        self._server = ThreadingHTTPServer(("127.0.0.1", port), self._handler_class())
        self._server.daemon_threads = True
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        host, port = self._server.server_address[:2]
        return f"http://{host}:{port}"

    def start(self) -> RestStandIn:
        self._thread = threading.Thread(target=self._server.serve_forever, args=(0.05,),
                                        name="rest-standin", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        if self._thread is None:
            return
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=2.0)
        self._thread = None

    def __enter__(self) -> RestStandIn:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- the simulated robot ------------------------------------------------------
    def advance(self) -> None:
        """Integrate the pose up to now, stopping at the refresh deadline."""
        with self.lock:
            now = self.clock.now()
            deadline = self._last_command + self.timeout
            if any(self.velocity) and now > deadline:
                self._integrate(max(0.0, deadline - self._t))
                self._t = max(self._t, deadline)
                self.velocity = (0.0, 0.0, 0.0)
                self.stops += 1
            self._integrate(now - self._t)
            self._t = now

    def _integrate(self, dt: float) -> None:
        vx, vy, w = self.velocity
        x, y, th = self.pose
        mid = th + 0.5 * w * dt
        self.pose = [x + (math.cos(mid) * vx - math.sin(mid) * vy) * dt,
                     y + (math.sin(mid) * vx + math.cos(mid) * vy) * dt, th + w * dt]

    def _omnidrive(self, body) -> None:
        self.advance()
        with self.lock:
            self.velocity = tuple(float(v) for v in body[:3])
            self._last_command = self.clock.now()
            self.commands.append((self._last_command, list(self.velocity)))

    def moving(self) -> bool:
        self.advance()
        with self.lock:
            return any(self.velocity)

    # -- HTTP -------------------------------------------------------------------------
    def _get(self, path: str):
        self.advance()
        with self.lock:
            self.seq += 1
            if path == "/data/odometry":
                return [*self.pose, *self.velocity, self.seq]
            if path == "/data/bumper":
                return {"value": self.bumper}
            if path == "/data/distancesensorarray":
                return list(self.distances)
            if path == "/data/analoginputarray":
                return [0.0] * 8
            if path in ("/data/digitalinputarray", "/data/digitaloutputstatus"):
                return [False] * 8
            if path == "/data/relaystatus":
                return [False, False]
            if path == "/data/imageversion":
                return {"version": "rll-bt stand-in"}
            if path == "/data/scan0":
                n = len(self.scan_ranges)
                inc = 2 * math.pi / n
                return {"seq": self.seq, "stamp": self.clock.epoch(), "angle_min": -math.pi,
                        "angle_max": -math.pi + inc * (n - 1), "angle_increment": inc,
                        "time_increment": 0.0, "scan_time": 0.1, "range_min": 0.05,
                        "range_max": 5.6, "ranges": [float(r) for r in self.scan_ranges],
                        "intensities": []}
        return None

    def _jpeg(self) -> bytes:
        import cv2
        w, h = self.image_size
        img = np.zeros((h, w, 3), np.uint8)
        img[:, : w // 2] = (0, 0, 255)      # left half red (BGR)
        img[:, w // 2:] = (0, 255, 0)       # right half green
        ok, buf = cv2.imencode(".jpg", img)
        return buf.tobytes() if ok else b""

    def _handler_class(self):
        standin = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):   # keep test output clean
                pass

            def _reply(self, code: int, body: bytes, ctype: str = "application/json") -> None:
                self.send_response(code)
                self.send_header("Content-Type", ctype)
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self):
                path = self.path.split("?", 1)[0]
                standin.requests.append(("GET", path))
                if path == "/cam0":
                    return self._reply(200, standin._jpeg(), "image/jpeg")
                data = standin._get(path)
                if data is None:
                    return self._reply(404, b'{"error": "not found"}')
                self._reply(200, json.dumps(data).encode())

            def _set(self):
                path = self.path.split("?", 1)[0]
                standin.requests.append((self.command, path))
                length = int(self.headers.get("Content-Length") or 0)
                try:
                    body = json.loads(self.rfile.read(length) or b"null")
                except ValueError:
                    return self._reply(400, b'{"error": "bad json"}')
                if path != "/data/omnidrive":
                    return self._reply(404, b'{"error": "not found"}')
                if (not isinstance(body, list) or len(body) != 3
                        or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in body)):
                    return self._reply(400, b'{"error": "expected [vx, vy, omega]"}')
                standin._omnidrive(body)
                self._reply(200, b"{}")

            do_POST = do_PUT = _set

        return Handler
