"""The one small interface every transport offers.

A transport carries encoded frames (UDP, TCP, or the in-process bus) and
hands back decoded messages:

- ``send(msg)``: encode and send; returns True when the frame left (False if
  e.g. a stream is not connected).  Raises only for the caller's mistakes
  (:class:`~rll_bt.comm.errors.FrameTooLarge`, no ``CompType``, unset required
  fields).
- ``receive() -> list[Received]``: everything that arrived since the last
  call, oldest first.  Never raises and never blocks.
- ``events() -> list[LinkEvent]``: stream connects and disconnects.
- ``wait(timeout)``: block up to ``timeout`` wall seconds until something may
  have arrived (returns at once on the bus).
- ``close()``.
- ``stats``: the :class:`~rll_bt.comm.stats.DropStats` of dropped frames.

Socket transports can also run a background thread: ``start(callback)``
delivers each :class:`Received` to ``callback`` from that thread (or queues it
for ``receive()`` when ``callback`` is None); ``stop()`` ends it.
"""
from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from ..clock import Clock, WallClock
from .codec import Decoded, FrameCodec
from .crypto import TEAM_CIPHER
from .stats import DropStats

log = logging.getLogger("rll_bt.comm")

CONNECTED, DISCONNECTED = "connected", "disconnected"


@dataclass(frozen=True)
class Received:
    """One decoded message.

    ``channel``: the transport's channel name ("public", "team", "stream", ...).
    ``source``: who sent it: ``(ip, port)`` for UDP, the client id (int) on a
    stream server, the server address on a stream client, the sending
    endpoint's name on a bus channel.
    ``time``: the transport clock's ``now()`` at receipt, seconds.
    ``cipher``: the frame's cipher id (0 = plain).
    """

    msg: Any
    channel: str
    source: Any
    comp_id: int
    msg_type: int
    time: float
    cipher: int = 0

    @property
    def type_name(self) -> str:
        """The message's short type name, e.g. ``"GameState"``."""
        return self.msg.DESCRIPTOR.name

    @classmethod
    def of(cls, d: Decoded, channel: str, source: Any, time: float) -> Received:
        return cls(d.msg, channel, source, d.comp_id, d.msg_type, time, d.cipher)


@dataclass(frozen=True)
class LinkEvent:
    """A stream peer came or went: ``kind`` is "connected" or "disconnected";
    ``peer`` is the client id (server side) or the server address (client side)."""

    kind: str
    peer: Any
    channel: str
    time: float


class CryptoSwitch:
    """Mixin for transports holding a :class:`~rll_bt.comm.codec.FrameCodec` as ``codec``:
    switch the team-channel encryption on or off at run time."""

    codec: FrameCodec

    def set_crypto(self, key: str | bytes, cipher: int | str = TEAM_CIPHER) -> None:
        """Encrypt with ``key`` from now on and drop plain frames (e.g. once GameState
        names our team)."""
        self.codec.set_crypto(key, cipher)

    def clear_crypto(self) -> None:
        """Send and accept plain frames from now on."""
        self.codec.clear_crypto()

    @property
    def encrypted(self) -> bool:
        return self.codec.encrypted


@runtime_checkable
class Transport(Protocol):
    channel: str
    stats: DropStats

    def send(self, msg) -> bool: ...
    def receive(self) -> list[Received]: ...
    def events(self) -> list[LinkEvent]: ...
    def wait(self, timeout: float) -> bool: ...
    def close(self) -> None: ...


class PumpedTransport:
    """Base of the socket transports: a non-blocking ``_pump`` polled by
    ``receive()`` or by a background thread.

    Subclasses implement ``_pump()`` (read sockets, call :meth:`_deliver` and
    :meth:`_event`), ``_wait_io(timeout)`` (select on their sockets) and
    ``_close_io()``.
    """

    def __init__(self, channel: str, clock: Clock | None):
        self.channel = channel
        self.clock: Clock = clock if clock is not None else WallClock()
        self._queue: deque[Received] = deque()
        self._events: deque[LinkEvent] = deque()
        self._cond = threading.Condition()
        self._io_lock = threading.RLock()
        self._thread: threading.Thread | None = None
        self._running = False
        self._callback: Callable[[Received], None] | None = None
        self._closed = False

    # -- for subclasses -------------------------------------------------------
    def _deliver(self, item: Received) -> None:
        cb = self._callback
        if cb is not None:
            try:
                cb(item)
            except Exception:
                log.exception("%s: receive callback failed", self.channel)
            return
        with self._cond:
            self._queue.append(item)
            self._cond.notify_all()

    def _event(self, kind: str, peer: Any) -> None:
        with self._cond:
            self._events.append(LinkEvent(kind, peer, self.channel, self.clock.now()))
            self._cond.notify_all()

    def _pump(self) -> None:
        raise NotImplementedError

    def _wait_io(self, timeout: float) -> None:
        raise NotImplementedError

    def _close_io(self) -> None:
        raise NotImplementedError

    def _pump_locked(self) -> None:
        with self._io_lock:
            if not self._closed:
                self._pump()

    # -- the interface -------------------------------------------------------
    def receive(self) -> list[Received]:
        if self._thread is None:
            self._pump_locked()
        with self._cond:
            items = list(self._queue)
            self._queue.clear()
        return items

    def events(self) -> list[LinkEvent]:
        if self._thread is None:
            self._pump_locked()
        with self._cond:
            items = list(self._events)
            self._events.clear()
        return items

    def wait(self, timeout: float) -> bool:
        """Block up to ``timeout`` wall seconds; True if something is ready to receive."""
        if self._thread is not None:
            with self._cond:
                if not self._queue and not self._events:
                    self._cond.wait(timeout)
                return bool(self._queue or self._events)
        if self._queue or self._events:
            return True
        self._wait_io(timeout)
        self._pump_locked()
        return bool(self._queue or self._events)

    def start(self, callback: Callable[[Received], None] | None = None) -> None:
        """Read in a daemon thread; deliver to ``callback`` (or queue for ``receive()``)."""
        if self._thread is not None:
            raise RuntimeError(f"{self.channel}: already started")
        self._callback = callback
        self._running = True
        self._thread = threading.Thread(target=self._run, name=f"rll_bt.comm {self.channel}",
                                        daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while self._running:
            try:
                self._wait_io(0.05)
                self._pump_locked()
            except Exception:
                log.exception("%s: reader loop error", self.channel)

    def stop(self) -> None:
        """End the background thread (if any); the transport stays open."""
        self._running = False
        t, self._thread = self._thread, None
        if t is not None and t is not threading.current_thread():
            t.join(timeout=2.0)
        self._callback = None

    def close(self) -> None:
        self.stop()
        with self._io_lock:
            if not self._closed:
                self._closed = True
                self._close_io()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
