"""The camera: a grabber thread keeping the newest frame.

    cam = CameraGrabber("/dev/video0", intrinsics=..., extrinsics=...).start()
    frame = cam.latest()        # rll_bt.backend.CameraImage or None; never blocks

``source`` is what ``cv2.VideoCapture`` opens: a V4L2 device (an index or
``/dev/videoN``, opened with ``CAP_V4L2``), a video file, or a stream URL
(MJPEG over HTTP: read by :class:`.mjpeg_reader.MjpegCapture`, which keeps
each frame's capture time, ``X-Timestamp``; RTSP and other streams: FFmpeg, with
open and read time-outs so that a silent stream cannot hang the thread).  The
thread reads as fast as frames come (a file at its own frame rate) and keeps
only the newest, stamped with its capture time (the server's word), else with
the host time it arrived minus ``latency``; a tick never waits for the
camera.  A failed read, or no frame for ``timeout`` seconds, counts as a
lost camera: it is released and reopened every ``reopen_interval``.  A file
that ends starts again (``loop``).
"""
from __future__ import annotations

import logging
import math
import os
import re
import threading
import time
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from rll_bt.backend import CameraExtrinsics, CameraImage, CameraIntrinsics
from rll_bt.clock import Clock, WallClock

from .calibration import scaled
from .mjpeg_reader import MjpegCapture

log = logging.getLogger(__name__)
#: a capture time more than this (s) before a frame arrived is another machine's clock: not used
MAX_AGE = 2.0


@dataclass
class CameraStats:
    connected: bool = False
    frames: int = 0
    connects: int = 0
    losses: int = 0
    last_error: str = ""
    last_frame_at: float = math.nan
    rate: float = 0.0
    size: tuple[int, int] = (0, 0)


def _open(source, open_timeout: float, read_timeout: float):
    import cv2
    if isinstance(source, int) or (isinstance(source, str) and re.fullmatch(r"/dev/video\d+", source)):
        return cv2.VideoCapture(source, cv2.CAP_V4L2)
    if isinstance(source, str) and source.startswith("http://"):
        cap = MjpegCapture(source, open_timeout, read_timeout)      # keeps each frame's capture time
        if cap.isOpened():
            return cap
        log.debug("%s: %s; trying FFmpeg", source, cap.error)
    params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, int(open_timeout * 1000),
              cv2.CAP_PROP_READ_TIMEOUT_MSEC, int(read_timeout * 1000)]
    return cv2.VideoCapture(source, cv2.CAP_FFMPEG, params)


class CameraGrabber:
    def __init__(self, source, *, intrinsics: CameraIntrinsics | None = None,
                 extrinsics: CameraExtrinsics | None = None, name: str = "front", clock: Clock | None = None,
                 hfov: float = math.radians(60.0), timeout: float = 1.0, reopen_interval: float = 0.5,
                 latency: float = 0.0, loop: bool = True, size: tuple[int, int] | None = None):
        self.source = int(source) if isinstance(source, str) and source.isdigit() else source
        self.intrinsics = intrinsics
        self.extrinsics = extrinsics or CameraExtrinsics()
        self.name = name
        self.clock = clock or WallClock()
        self.hfov = hfov
        self.timeout = timeout
        self.reopen_interval = reopen_interval
        self.latency = latency
        self.loop = loop
        self.size = size
        self._file = isinstance(self.source, str) and os.path.isfile(self.source)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._frame: CameraImage | None = None
        self._stats = CameraStats()
        self._arrivals: deque = deque(maxlen=30)
        self._intr_cache: dict = {}

    def describe(self) -> str:
        return f"camera {self.name} ({self.source})"

    def start(self, wait: float | None = None) -> CameraGrabber:
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"camera-{self.name}", daemon=True)
        self._thread.start()
        if wait is not None:
            end = self.clock.now() + wait
            while self.latest() is None:
                if self.clock.now() >= end:
                    self.close()
                    raise OSError(f"{self.describe()}: no frame within {wait:g} s "
                                  f"({self.stats().last_error or 'nothing arrived'})")
                self._stop.wait(0.01)
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=3.0)
            self._thread = None

    def latest(self) -> CameraImage | None:
        with self._lock:
            return self._frame

    def stats(self) -> CameraStats:
        with self._lock:
            s = replace(self._stats)
        if len(self._arrivals) >= 2 and self.clock.now() - self._arrivals[-1] < 2.0:
            span = self._arrivals[-1] - self._arrivals[0]
            s.rate = (len(self._arrivals) - 1) / span if span > 0 else 0.0
        return s

    def healthy(self, stale: float) -> bool:
        with self._lock:
            last = self._stats.last_frame_at
            return self._stats.connected and not math.isnan(last) and self.clock.now() - last <= stale

    def _intrinsics(self, w: int, h: int) -> CameraIntrinsics:
        key = (w, h)
        if key not in self._intr_cache:
            base = self.intrinsics or CameraIntrinsics.from_fov(w, h, self.hfov)
            self._intr_cache[key] = scaled(base, w, h)
        return self._intr_cache[key]

    def _stamp(self, arrived: float, sent: float | None) -> float:
        """A frame's capture time on :attr:`clock`: from the time the server says it captured
        it (``sent``, s since the epoch; its clock is this machine's: the camera server runs on
        the robot) when that is a plausible age, else its arrival minus ``latency``."""
        if sent is not None:
            age = time.time() - sent
            if -0.05 <= age <= MAX_AGE:
                return arrived - max(age, 0.0)
        return arrived - self.latency

    def _run(self) -> None:
        import cv2
        while not self._stop.is_set():
            cap = _open(self.source, max(self.timeout, 1.0), self.timeout)
            if not cap.isOpened():
                cap.release()
                with self._lock:
                    self._stats.last_error = "cannot open"
                self._stop.wait(self.reopen_interval)
                continue
            if self.size is not None:
                cap.set(cv2.CAP_PROP_FRAME_WIDTH, self.size[0])
                cap.set(cv2.CAP_PROP_FRAME_HEIGHT, self.size[1])
            fps = cap.get(cv2.CAP_PROP_FPS) if self._file else 0.0
            period = 1.0 / fps if fps and fps > 0 else 0.0
            with self._lock:
                self._stats.connected = True
                self._stats.connects += 1
            log.info("%s opened", self.describe())
            try:
                self._read_loop(cap, period)
            finally:
                cap.release()
                with self._lock:
                    self._stats.connected = False
            self._stop.wait(self.reopen_interval)

    def _read_loop(self, cap, period: float) -> None:
        import cv2
        last = self.clock.now()
        while not self._stop.is_set():
            ok, image = cap.read()
            now = self.clock.now()
            if not ok or image is None:
                if self._file and self.loop and cap.get(cv2.CAP_PROP_POS_FRAMES) > 0:
                    cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
                    continue
                with self._lock:
                    self._stats.losses += 1
                    self._stats.last_error = "read failed (camera gone or stream ended)"
                log.warning("%s: read failed; reopening", self.describe())
                return
            if image.ndim == 2:
                image = np.repeat(image[:, :, None], 3, axis=2)
            h, w = image.shape[:2]
            frame = CameraImage(self._stamp(now, getattr(cap, "timestamp", None)), image,
                                self._intrinsics(w, h), self.extrinsics, self.name)
            with self._lock:
                self._frame = frame
                self._stats.frames += 1
                self._stats.last_frame_at = now
                self._stats.size = (w, h)
            self._arrivals.append(now)
            if now - last > self.timeout:
                log.debug("%s: %.2f s between frames", self.describe(), now - last)
            last = now
            if period:
                self._stop.wait(period)
