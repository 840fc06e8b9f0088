"""A camera as an MJPEG stream over HTTP (what IP cameras and ``mjpg-streamer``
serve): the emulated robot camera.

    server = MjpegServer(frame_source, fps=10).start()
    server.url          # http://127.0.0.1:PORT/stream.mjpg, opened by cv2.VideoCapture

``frame_source()`` returns a BGR image, or (image, when it was taken on the
server's ``clock``), or None: nothing new to send; it is asked again a few
milliseconds later, so a frame goes out as soon as it is there, as a camera
sends what it captures.
Every client gets ``multipart/x-mixed-replace`` parts, each a JPEG with its
``Content-Type``, ``Content-Length`` and ``X-Timestamp`` (the capture time in
seconds since the epoch, as ``mjpg-streamer`` sends it).  ``/snapshot.jpg`` serves one frame.  Faults:
:meth:`unplug` drops every client and refuses new ones for a while,
:meth:`set_silent` keeps the connections open without sending frames.
"""
from __future__ import annotations

import logging
import socket
import threading
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import cv2
import numpy as np

from rll_bt.clock import Clock, WallClock

log = logging.getLogger(__name__)
BOUNDARY = "rllbtframe"
#: how soon the source is asked again when it had no new frame (s)
NEW_FRAME_POLL = 0.005


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True


class MjpegServer:
    def __init__(self, frame_source: Callable[[], np.ndarray | None], *, fps: float = 10.0,
                 host: str = "127.0.0.1", port: int = 0, quality: int = 85, clock: Clock | None = None):
        self.frame_source = frame_source
        self.fps = fps
        self.host, self.port = host, port
        self.quality = quality
        self.clock = clock or WallClock()
        self.silent = False
        self.frames_sent = 0
        self.clients = 0
        self._generation = 0
        self._lock = threading.Lock()
        self._frame: tuple[float, bytes] | None = None
        self._cond = threading.Condition(self._lock)
        self._stop = threading.Event()
        self._server: _Server | None = None
        self._threads: list[threading.Thread] = []
        self._unplug_timer: threading.Timer | None = None

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/stream.mjpg"

    def start(self) -> MjpegServer:
        self._stop.clear()
        self._serve()
        t = threading.Thread(target=self._capture_loop, name="mjpeg-capture", daemon=True)
        t.start()
        self._threads.append(t)
        return self

    def _serve(self) -> None:
        server = _Server((self.host, self.port), self._handler())
        self.port = server.server_address[1]
        self._server = server
        t = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05},
                             name=f"mjpeg:{self.port}", daemon=True)
        t.start()
        self._threads.append(t)

    def _shutdown_server(self) -> None:
        server, self._server = self._server, None
        if server is not None:
            with self._cond:
                self._generation += 1          # handlers of the old server end
                self._cond.notify_all()
            server.shutdown()
            server.server_close()

    def stop(self) -> None:
        self._stop.set()
        if self._unplug_timer is not None:
            self._unplug_timer.cancel()
        self._shutdown_server()
        with self._cond:
            self._cond.notify_all()
        for t in self._threads:
            t.join(timeout=2.0)
        self._threads = []

    def unplug(self, duration: float) -> None:
        """No camera for ``duration`` seconds: clients dropped, connects refused."""
        self._shutdown_server()
        self._unplug_timer = threading.Timer(duration, self._replug)
        self._unplug_timer.daemon = True
        self._unplug_timer.start()

    def _replug(self) -> None:
        if not self._stop.is_set() and self._server is None:
            self._serve()

    @property
    def plugged(self) -> bool:
        return self._server is not None

    def set_silent(self, silent: bool) -> None:
        self.silent = silent

    # -- frames ----------------------------------------------------------------------
    def _capture_loop(self) -> None:
        period = 1.0 / self.fps
        next_t = self.clock.now()
        while not self._stop.is_set():
            now = self.clock.now()
            if now < next_t:
                self._stop.wait(min(period, next_t - now))
                continue
            next_t = max(next_t + period, now)
            if self.silent or self.clients == 0:
                continue
            try:
                image = self.frame_source()
            except Exception:
                log.exception("camera frame source failed")
                continue
            taken = now
            if isinstance(image, tuple):            # (image, when it was taken on this clock)
                image, taken = image
            if image is None:
                # nothing new yet: look again soon rather than a whole period later (the
                # emulated camera's world renders on its own clock; polled once a period,
                # a frame waited up to a period, 0.2 s at 5 fps, and the tags seen while
                # turning put the stations' poses 0.3 m and 11 degrees off)
                next_t = now + min(period, NEW_FRAME_POLL)
                continue
            ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.quality])
            if not ok:
                continue
            with self._cond:
                self._frame = (self._epoch(taken, now), jpeg.tobytes())
                self._cond.notify_all()

    def _epoch(self, taken: float, now: float) -> float:
        """``taken`` (this clock) in seconds since the epoch, as ``X-Timestamp`` says it."""
        epoch = getattr(self.clock, "epoch", None)
        return taken + (epoch() - now) if epoch is not None else taken

    def _next_frame(self, last: float | None, generation: int) -> tuple[float, bytes] | None:
        with self._cond:
            while not self._stop.is_set() and generation == self._generation:
                f = self._frame
                if f is not None and f[0] != last and not self.silent:
                    return f
                self._cond.wait(0.5)
        return None

    def _handler(self):
        outer = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.0"

            def log_message(self, *args):
                pass

            def do_GET(self):
                generation = outer._generation
                path = self.path.split("?")[0]
                if path not in ("/stream.mjpg", "/snapshot.jpg", "/"):
                    self.send_error(404, "use /stream.mjpg or /snapshot.jpg")
                    return
                outer.clients += 1
                try:
                    if path == "/snapshot.jpg":
                        f = outer._next_frame(None, generation)
                        if f is None:
                            self.send_error(503, "no frame")
                            return
                        self.send_response(200)
                        self.send_header("Content-Type", "image/jpeg")
                        self.send_header("Content-Length", str(len(f[1])))
                        self.send_header("X-Timestamp", f"{f[0]:.6f}")
                        self.end_headers()
                        self.wfile.write(f[1])
                        return
                    self.send_response(200)
                    self.send_header("Content-Type", f"multipart/x-mixed-replace;boundary={BOUNDARY}")
                    self.send_header("Cache-Control", "no-cache")
                    self.end_headers()
                    last = None
                    while True:
                        f = outer._next_frame(last, generation)
                        if f is None:
                            break
                        last = f[0]
                        self.wfile.write(f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: "
                                         f"{len(f[1])}\r\nX-Timestamp: {f[0]:.6f}\r\n\r\n".encode())
                        self.wfile.write(f[1] + b"\r\n")
                        self.wfile.flush()
                        outer.frames_sent += 1
                except (TimeoutError, BrokenPipeError, ConnectionResetError, OSError):
                    pass
                finally:
                    outer.clients -= 1
                    if generation != outer._generation:
                        try:
                            self.connection.shutdown(socket.SHUT_RDWR)
                        except OSError:
                            pass
        return Handler
