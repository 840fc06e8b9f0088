"""What a device emulator's serving thread shares, whatever its link (a pty,
a TCP port): a lock, a clock, the cable that can be pulled for a while
(:meth:`Pluggable.unplug`, :meth:`Pluggable.replug`), a device that goes
silent (:meth:`Pluggable.set_silent`), and the thread that runs
:meth:`Pluggable._step` until :meth:`Pluggable.stop`.

A subclass implements ``_step()`` (serve once; it looks at
``_unplugged_until`` itself), ``_close_link()`` (let go of the link on stop),
``plugged`` and ``thread_name``.
"""
from __future__ import annotations

import logging
import threading

from rll_bt.clock import Clock, WallClock

log = logging.getLogger(__name__)


class Pluggable:
    def __init__(self, clock: Clock | None = None):
        self.clock = clock or WallClock()
        self.lock = threading.RLock()
        self.silent = False
        self.connects = 0
        self._unplugged_until: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    thread_name = "device"

    def _start_thread(self) -> None:
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=self.thread_name, daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        self._close_link()

    def unplug(self, duration: float) -> None:
        """Pull the cable for ``duration`` seconds (``inf``: until :meth:`replug`)."""
        with self.lock:
            self._unplugged_until = self.clock.now() + duration

    def replug(self) -> None:
        with self.lock:
            if self._unplugged_until is not None:
                self._unplugged_until = self.clock.now()

    def set_silent(self, silent: bool) -> None:
        """Keep the link but send nothing (a hung device)."""
        with self.lock:
            self.silent = silent

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self._step()
            except Exception:              # keep serving the host
                log.exception("%s: step failed", self.thread_name)
                self._stop.wait(0.05)

    def _step(self) -> None:
        raise NotImplementedError

    def _close_link(self) -> None:
        raise NotImplementedError
