"""The live page's web server: the standard library's ``http.server`` in a thread.

- ``GET /``: the page (``static/index.html``), ``GET /static/NAME``: its
  script, style and icon, shipped in the package (no build step);
- ``GET /state``: the whole :class:`~.state.ViewState` as JSON;
- ``GET /events``: server-sent events: the whole state first, then what
  changed (at most :attr:`ViewServer.max_rate` a second), so the page
  follows a game as it is played;
- ``POST /control`` (a replay only): ``{"op": "play" | "pause" | "seek" |
  "speed", "t": s, "speed": x}`` steers the playback (:mod:`.sources`).

It binds 127.0.0.1 unless told otherwise: the page and its state are
for the people at this machine.
"""
from __future__ import annotations

import json
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources

from .state import ViewState

TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
         ".css": "text/css; charset=utf-8", ".svg": "image/svg+xml"}


def asset(name: str) -> bytes | None:
    """A file of ``static/`` (None for anything else)."""
    if "/" in name or "\\" in name or name.startswith(".") or not any(name.endswith(s) for s in TYPES):
        return None
    f = resources.files("games.view").joinpath("static", name)
    return f.read_bytes() if f.is_file() else None


class ViewServer:
    """Serves ``state`` on ``host:port`` (0: any free port) until :meth:`close`.
    ``control``: a replay's playback (``control(dict) -> dict``), or None."""

    max_rate = 10.0

    def __init__(self, state: ViewState, port: int = 0, host: str = "127.0.0.1", control=None):
        self.state = state
        self.control = control
        self.stopping = threading.Event()
        server = self

        class Handler(_Handler):
            view = server
        self.httpd = ThreadingHTTPServer((host, int(port)), Handler)
        self.httpd.daemon_threads = True
        self.host = host
        self.port = self.httpd.server_address[1]
        self._thread = threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.2},
                                        name="rll-bt view", daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        host = "localhost" if self.host in ("127.0.0.1", "0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}/"

    def close(self) -> None:
        self.stopping.set()
        with self.state._lock:
            self.state._lock.notify_all()
        self.httpd.shutdown()
        self.httpd.server_close()
        self._thread.join(5)

    def __enter__(self) -> ViewServer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class _Handler(BaseHTTPRequestHandler):
    view: ViewServer
    protocol_version = "HTTP/1.1"
    server_version = "rll-bt-view"

    def log_message(self, format, *args) -> None:       # quiet: the game's progress owns stderr
        pass

    def _send(self, code: int, body: bytes, ctype: str = "application/json") -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _json(self, data, code: int = 200) -> None:
        self._send(code, json.dumps(data, separators=(",", ":")).encode())

    def do_GET(self) -> None:
        path = self.path.split("?", 1)[0]
        if path in ("/", "/index.html"):
            self._send(200, asset("index.html"), TYPES[".html"])
        elif path.startswith("/static/"):
            name = path[len("/static/"):]
            body = asset(name)
            if body is None:
                self._json({"error": f"no such file: {name}"}, 404)
            else:
                self._send(200, body, TYPES["." + name.rsplit(".", 1)[-1]])
        elif path == "/state":
            self._json(self.view.state.snapshot())
        elif path == "/events":
            self._events()
        else:
            self._json({"error": f"not found: {path}"}, 404)

    def do_POST(self) -> None:
        if self.path != "/control":
            self._json({"error": f"not found: {self.path}"}, 404)
            return
        if self.view.control is None:
            self._json({"error": "a live game cannot be steered"}, 409)
            return
        try:
            length = int(self.headers.get("Content-Length", "0"))
            cmd = json.loads(self.rfile.read(length) or b"{}")
            if not isinstance(cmd, dict):
                raise ValueError("not an object")
            self._json(self.view.control(cmd))
        except (ValueError, KeyError, TypeError) as exc:
            self._json({"error": f"bad command: {exc}"}, 400)

    def _events(self) -> None:
        view, state = self.view, self.view.state
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
        cursor = None
        idle = 0.0
        try:
            while not view.stopping.is_set():
                delta = state.changes(cursor)
                if delta is not None:
                    cursor = delta["cursor"]
                    self.wfile.write(b"data: " + json.dumps(delta, separators=(",", ":")).encode() + b"\n\n")
                    self.wfile.flush()
                    idle = 0.0
                    view.stopping.wait(1.0 / view.max_rate)
                    continue
                state.wait(cursor["v"], 1.0)
                idle += 1.0
                if idle >= 15.0:                       # a comment keeps proxies and the browser content
                    self.wfile.write(b": keepalive\n\n")
                    self.wfile.flush()
                    idle = 0.0
        except (BrokenPipeError, ConnectionResetError, ConnectionAbortedError, OSError):
            pass


__all__ = ["ViewServer", "asset"]
