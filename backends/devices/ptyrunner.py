"""A device model behind a pseudo-terminal, as a USB serial device looks to
its host.

The model has ``receive(data, now)``, ``take_output() -> bytes``,
``advance(now)`` and optionally ``next_due() -> float | None`` (when it next
has something to send on its own); :class:`PtyRunner` publishes the pty's
slave under the symlink ``link`` (what the host opens, like
``/dev/ttyACM1``), feeds the model what the host writes and writes back what
it produces, in a thread that sleeps until the host writes or the model is
due (at most ``idle`` seconds: the host's opening and a pulled cable's
return are looked at that often), or ``wake`` (anything with ``fileno()``
and ``drain()``, :class:`~backends.devices.laser.source.CastSignal`) says
the model has something new to send.
Faults: :meth:`unplug` removes the device for a while (the link and the pty
go away, as when the cable is pulled; a fresh pty comes back behind the same
link), :meth:`set_silent` keeps the port but sends nothing (a hung device).
The pty itself is :class:`backends.robotino.emulator.PtyDevice`.
"""
from __future__ import annotations

import logging
import os
import select

from rll_bt.clock import Clock

from .pluggable import Pluggable

log = logging.getLogger(__name__)


class PtyRunner(Pluggable):
    def __init__(self, model, link: str, *, clock: Clock | None = None, period: float = 0.002,
                 on_connect=None, idle: float = 0.05, wake=None):
        from backends.robotino.emulator import PtyDevice
        super().__init__(clock)
        self.model = model
        self.pty = PtyDevice(link)
        self.period = period            # the shortest sleep (a model due now is served this late at most)
        self.idle = idle                # the longest sleep
        self.on_connect = on_connect
        self.wake = wake
        self.bytes_in = self.bytes_out = 0

    @property
    def link(self) -> str:
        return self.pty.link

    @property
    def thread_name(self) -> str:
        return f"pty:{os.path.basename(self.link)}"

    def start(self) -> PtyRunner:
        os.makedirs(os.path.dirname(self.link) or ".", exist_ok=True)
        self.pty.open()
        self._start_thread()
        return self

    def _close_link(self) -> None:
        self.pty.close()

    @property
    def plugged(self) -> bool:
        return self.pty.is_open

    def _wait(self, now: float) -> float:
        """How long to wait for the host: until the model is due, at least ``period``, at most ``idle``."""
        due = getattr(self.model, "next_due", None)
        when = due() if due is not None else now + self.period
        if when is None:
            return self.idle
        return min(self.idle, max(self.period, when - now))

    def _step(self) -> None:
        now = self.clock.now()
        with self.lock:
            until = self._unplugged_until
            if until is not None:
                if self.pty.is_open and now < until:
                    log.info("%s: unplugged", self.link)
                    self.pty.close()
                elif not self.pty.is_open and now >= until:
                    self._unplugged_until = None
                    self.pty.open()
                    log.info("%s: plugged in again", self.link)
            if not self.pty.is_open:
                wait = self.idle if until is None else min(self.idle, max(until - now, self.period))
                self._stop.wait(wait)
                return
            was = self.pty.connected
            self.pty.connected = self.pty.poll_connected()
            if was and not self.pty.connected:
                self.pty.hung_up()
            if self.pty.connected and not was:
                self.connects += 1
                if self.on_connect is not None:
                    self.on_connect(now)
        fd = self.pty.master
        if not self.pty.connected:
            self._stop.wait(self.idle)
            return
        watch = [fd] if self.wake is None else [fd, self.wake]
        ready, _, _ = select.select(watch, [fd] if self.pty.pending else [], [], self._wait(now))
        now = self.clock.now()
        if self.wake is not None and self.wake in ready:
            self.wake.drain()
        with self.lock:
            if not self.pty.is_open:
                return
            self.pty.flush()
            if fd in ready:
                data = self.pty.read()
                if data:
                    self.bytes_in += len(data)
                    if not self.silent:
                        self.model.receive(data, now)
            self.model.advance(now)
            out = self.model.take_output()
            if out and not self.silent and self.pty.connected:
                self.pty.write(out)
                self.bytes_out += len(out)
