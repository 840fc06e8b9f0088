"""An MJPEG stream over HTTP read with each frame's capture time.

An MJPEG camera server (``mjpg-streamer``, IP cameras, the emulated robot
camera of :mod:`.mjpeg`) sends ``multipart/x-mixed-replace`` parts, each a
JPEG with its ``Content-Length`` and, from ``mjpg-streamer`` and ours, an
``X-Timestamp``: when the frame was captured, in seconds since the epoch on
the server's clock.  OpenCV's FFmpeg back-end reads such a stream but drops
the part headers, so a frame could only be stamped when it arrived: 0.05 to
0.15 s after the robot stood where it was taken, which put the stations seen
while turning 0.2 m off.  :class:`MjpegCapture` reads the stream itself and
keeps the capture time (``timestamp``) beside each frame; it looks like the
part of ``cv2.VideoCapture`` the grabber uses (``isOpened``, ``read``,
``release``, ``get``).

:class:`PartReader` is the parser, fed bytes as they come: it never raises on
what it is fed; a part it cannot make sense of is skipped (counted in
``bad``), an oversized one too.
"""
from __future__ import annotations

import math
import re
import socket
from urllib.parse import urlsplit

import numpy as np

#: a part larger than this (bytes) is not a camera frame: skipped
MAX_PART = 8 * 1024 * 1024
#: the headers of a part longer than this (bytes): not a part
MAX_HEADERS = 8 * 1024


class PartReader:
    """Incremental multipart parser: :meth:`feed` bytes, get (headers, body) parts
    that carry a ``Content-Length`` (header names in lower case)."""

    def __init__(self, boundary: bytes):
        self.marker = b"--" + boundary
        self.buf = bytearray()
        self.bad = 0
        self._headers: dict[str, str] | None = None
        self._length = 0

    def feed(self, data: bytes) -> list[tuple[dict[str, str], bytes]]:
        self.buf += data
        out = []
        while True:
            if self._headers is None and not self._find_headers():
                return out
            if len(self.buf) < self._length:
                return out
            out.append((self._headers, bytes(self.buf[:self._length])))
            del self.buf[:self._length]
            self._headers = None

    def _find_headers(self) -> bool:
        """Find the next part's headers; False: more bytes are needed."""
        while True:
            start = self.buf.find(self.marker)
            if start < 0:
                keep = len(self.marker) - 1            # a marker may be cut at the end
                if len(self.buf) > keep:
                    del self.buf[:len(self.buf) - keep]
                return False
            end = self.buf.find(b"\r\n\r\n", start)
            if end < 0:
                if len(self.buf) - start > MAX_HEADERS:
                    self.bad += 1
                    del self.buf[:start + len(self.marker)]
                    continue
                del self.buf[:start]
                return False
            head = bytes(self.buf[start + len(self.marker):end]).decode("latin-1")
            del self.buf[:end + 4]
            headers = {}
            for line in head.split("\r\n"):
                name, sep, value = line.partition(":")
                if sep:
                    headers[name.strip().lower()] = value.strip()
            try:
                length = int(headers.get("content-length", ""))
            except ValueError:
                length = -1
            if not 0 <= length <= MAX_PART:
                self.bad += 1
                continue
            self._headers, self._length = headers, length
            return True


def part_timestamp(headers: dict[str, str]) -> float | None:
    """A part's ``X-Timestamp`` (s since the epoch), or None (absent, not a finite number)."""
    try:
        t = float(headers.get("x-timestamp", ""))
    except ValueError:
        return None
    return t if math.isfinite(t) else None


def _boundary(content_type: str) -> bytes | None:
    m = re.search(r'boundary="?([^";,]+)"?', content_type or "", re.IGNORECASE)
    if not m or not content_type.lower().startswith("multipart/"):
        return None
    b = m.group(1).strip()
    return (b[2:] if b.startswith("--") else b).encode("latin-1")


class MjpegCapture:
    """``cv2.VideoCapture``'s reading side for an MJPEG stream over HTTP: :meth:`read`
    gives the next frame, ``timestamp`` its capture time (s since the epoch on the
    server's clock; None when the server sends none).  Not opened (``isOpened()``
    False, ``error`` says why) when the URL does not serve such a stream."""

    def __init__(self, url: str, open_timeout: float = 2.0, read_timeout: float = 1.0):
        self.url = url
        self.timestamp: float | None = None
        self.error = ""
        self._sock: socket.socket | None = None
        self._reader: PartReader | None = None
        self._parts: list = []
        u = urlsplit(url)
        host, port = u.hostname or "127.0.0.1", u.port or 80
        path = (u.path or "/") + (f"?{u.query}" if u.query else "")
        try:
            sock = socket.create_connection((host, port), timeout=open_timeout)
        except OSError as exc:
            self.error = f"cannot open: {exc}"
            return
        try:
            sock.sendall(f"GET {path} HTTP/1.0\r\nHost: {host}\r\nUser-Agent: rll-bt\r\n\r\n".encode("latin-1"))
            head = bytearray()
            while b"\r\n\r\n" not in head and len(head) < MAX_HEADERS:
                data = sock.recv(4096)
                if not data:
                    break
                head += data
        except OSError as exc:
            sock.close()
            self.error = f"cannot open: {exc}"
            return
        top, _, rest = bytes(head).partition(b"\r\n\r\n")
        lines = top.decode("latin-1").split("\r\n")
        status = lines[0].split(" ")
        headers = {n.strip().lower(): v.strip() for n, _, v in (ln.partition(":") for ln in lines[1:])}
        boundary = _boundary(headers.get("content-type", ""))
        if len(status) < 2 or status[1] != "200" or boundary is None:
            sock.close()
            self.error = f"not an MJPEG stream ({lines[0][:60]!r}, {headers.get('content-type')!r})"
            return
        sock.settimeout(read_timeout)           # a silent stream ends a read
        self._sock = sock
        self._reader = PartReader(boundary)
        self._parts = self._reader.feed(rest)

    def isOpened(self) -> bool:
        return self._sock is not None

    def read(self) -> tuple[bool, np.ndarray | None]:
        import cv2
        while self._sock is not None:
            while self._parts:
                headers, body = self._parts.pop(0)
                image = cv2.imdecode(np.frombuffer(body, np.uint8), cv2.IMREAD_COLOR) if body else None
                if image is None:
                    self._reader.bad += 1
                    continue
                self.timestamp = part_timestamp(headers)
                return True, image
            try:
                data = self._sock.recv(65536)
            except OSError:
                data = b""
            if not data:
                self.error = "the stream ended or went silent"
                return False, None
            self._parts = self._reader.feed(data)
            if len(self._parts) > 1:
                self._parts = self._parts[-1:]          # late: only the newest frame counts
        return False, None

    def get(self, _prop) -> float:
        return 0.0

    def set(self, _prop, _value) -> bool:
        return False

    def release(self) -> None:
        if self._sock is not None:
            try:
                self._sock.close()
            except OSError:
                pass
        self._sock = None
