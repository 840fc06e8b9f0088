"""A firmware-faithful Robotino 3 base (and optional gripper) on a pty.

:class:`RobotinoEmulator` opens a pseudo-terminal pair per device (raw mode)
and publishes each slave under a stable symlink (``device`` and
``gripper_device``), so a host opens it like ``/dev/ttyACM0``.  Closing the
port for a fault removes the link and the pty (the host sees the device
vanish, like an unplugged USB cable); reopening creates a fresh pty behind
the same link.  The base's behaviour is :class:`firmware.BaseFirmware`, the
gripper's :class:`arduino.GripperFirmware` (reset, i.e. HELLO and homing,
every time the host opens its port).

Use it in-process::

    with RobotinoEmulator(gripper=True) as emu:
        backend = open_backend("robotino", device=emu.device,
                               gripper_device=emu.gripper_device)
        ...
        x, y, theta = emu.ground_truth()

or from the command line: ``rll-bt robotino emulate [--gripper]``.
"""
from __future__ import annotations

import errno
import logging
import os
import random
import select
import shutil
import tempfile
import threading
import tty
from collections import deque

from rll_bt.clock import Clock, WallClock

from .arduino import GripperFirmware
from .faults import Faults, FaultStream
from .firmware import BaseFirmware
from .framing import HEAD

log = logging.getLogger(__name__)


class PtyDevice:
    """A pty pair whose slave is published as the symlink ``link``.

    What the device sends goes out whole: a message the pty cannot take now
    (the host has not read for a while and the line's buffer is full) waits
    in ``pending`` and goes out as the host reads (:meth:`flush`), as a USB
    device's data waits while the host does not poll; a new message that
    would take the waiting bytes past ``backlog`` is dropped whole (a device
    that cannot send skips it), never cut: a message cut mid-way reached a
    URG host as a corrupt data line, the laser was lost and the robot stopped.
    """

    def __init__(self, link: str, backlog: int = 1 << 16):
        self.link = link
        self.master: int | None = None
        self.slave_name = ""
        self.connected = False
        self.tx_overflow = 0            # bytes of whole messages dropped
        self.backlog = backlog
        self.pending = bytearray()

    @property
    def is_open(self) -> bool:
        return self.master is not None

    def open(self) -> None:
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        self.slave_name = os.ttyname(slave)
        os.close(slave)          # the host's open is what we wait for (POLLHUP clears)
        self.master = master
        self.connected = False
        tmp = f"{self.link}.{os.getpid()}.tmp"
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(self.slave_name, tmp)
        os.replace(tmp, self.link)

    def close(self) -> None:
        if os.path.lexists(self.link):
            try:
                os.unlink(self.link)
            except OSError:
                pass
        if self.master is not None:
            os.close(self.master)
        self.master = None
        self.connected = False
        self.pending.clear()

    def poll_connected(self) -> bool:
        """Whether a host holds the slave open (no POLLHUP on the master)."""
        if self.master is None:
            return False
        p = select.poll()
        p.register(self.master, select.POLLIN)
        events = p.poll(0)
        return not any(ev & select.POLLHUP for _, ev in events)

    def read(self) -> bytes:
        try:
            return os.read(self.master, 4096)
        except BlockingIOError:
            return b""
        except OSError as exc:
            if exc.errno == errno.EIO:      # the host closed its side
                self.hung_up()
                return b""
            raise

    def write(self, data: bytes) -> None:
        """Send one or more whole messages (see the class doc)."""
        if not data:
            return
        if self.pending and len(self.pending) + len(data) > self.backlog:
            self.tx_overflow += len(data)
            return
        self.pending += data
        self.flush()

    def hung_up(self) -> None:
        """The host closed its side: what waited for it is dropped."""
        self.connected = False
        self.pending.clear()

    def flush(self) -> None:
        """Send what waits, as far as the pty takes it now."""
        while self.pending and self.master is not None:
            try:
                n = os.write(self.master, self.pending)
            except BlockingIOError:
                return
            except OSError:
                self.connected = False
                self.pending.clear()
                return
            del self.pending[:n]


class _Endpoint:
    """One device: pty, faults in both directions, delayed output."""

    def __init__(self, name: str, link: str, faults: Faults, rng: random.Random):
        self.name = name
        self.pty = PtyDevice(link)
        self.faults = faults
        self.rx = FaultStream(faults, rng)
        self.tx = FaultStream(faults, rng)
        self.queue: deque = deque()
        self.closed_until: float | None = None
        self.connects = 0
        self.bytes_in = 0
        self.bytes_out = 0

    def send(self, data: bytes, now: float) -> None:
        if not data or not self.pty.connected:
            return
        data = self.tx.apply(data)
        if self.faults.delay_ms > 0:
            self.queue.append((now + self.faults.delay_ms / 1000.0, data))
        else:
            self.pty.write(data)
            self.bytes_out += len(data)

    def flush(self, now: float) -> None:
        while self.queue and self.queue[0][0] <= now:
            _, data = self.queue.popleft()
            if self.pty.connected:
                self.pty.write(data)
                self.bytes_out += len(data)
        self.pty.flush()

    def next_due(self) -> float | None:
        return self.queue[0][0] if self.queue else None


def arrival_times(data: bytes, last: float | None, now: float, spacing: float):
    """When the bytes of ``data``, read at ``now`` after a read at ``last``,
    reached the device: ``(time, chunk)``, one chunk per frame (split at each
    frame head).

    A microcontroller takes each byte as it arrives; the emulator's thread
    takes them when it is scheduled.  When it was late (a loaded machine, a
    busy interpreter) several frames wait in the pty together, and reading
    them all at ``now`` would count the delay against the host (a watchdog
    trip for a host that kept polling).  The frames are taken as arrived as
    late as possible: the last one now, each one before it ``spacing``
    earlier (the host's shortest poll cycle), never before ``last``.  A host
    that really went quiet and then sent one frame still trips the watchdog.
    """
    heads = [i for i, b in enumerate(data) if b == HEAD]
    if not heads or heads[0] != 0:
        heads.insert(0, 0)
    chunks = [data[a:b] for a, b in zip(heads, heads[1:] + [len(data)])]
    k = len(chunks)
    for i, chunk in enumerate(chunks):
        when = now - (k - 1 - i) * spacing
        if last is not None:
            when = max(when, last)
        yield when, chunk


class RobotinoEmulator:
    """Base firmware (and optionally the gripper sketch) behind ptys.

    ``faults`` apply to both directions of both links.  ``lock`` guards
    ``firmware`` and ``gripper``; the accessor methods take it themselves.
    """

    def __init__(self, *, gripper: bool = False, faults: Faults | None = None,
                 link_dir: str | None = None, clock: Clock | None = None,
                 firmware: BaseFirmware | None = None,
                 gripper_firmware: GripperFirmware | None = None, idle_period: float = 0.005,
                 host_spacing: float = 0.005, stall_stop: float | None = None, on_step=None):
        self.clock = clock or WallClock()
        self.faults = faults or Faults()
        self._own_dir = link_dir is None
        self.link_dir = link_dir or tempfile.mkdtemp(prefix="robotino-emu-")
        os.makedirs(self.link_dir, exist_ok=True)
        rng = random.Random(self.faults.seed)
        self.firmware = firmware or BaseFirmware(start=self.clock.now())
        self.gripper = (gripper_firmware or GripperFirmware()) if gripper else None
        self._base = _Endpoint("base", os.path.join(self.link_dir, "robotino-base"), self.faults, rng)
        self._grip = (_Endpoint("gripper", os.path.join(self.link_dir, "robotino-gripper"),
                                self.faults, rng) if gripper else None)
        self.idle_period = idle_period
        self.lock = threading.RLock()
        self.silent = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._next_close = None
        #: frames found waiting together are taken as sent this far apart (the
        #: host's shortest poll cycle), ending now: see :func:`arrival_times`
        self.host_spacing = host_spacing
        self._last_read: float | None = None
        self.stall_threshold = 0.1
        self.stalls = 0                 # reads more than stall_threshold after the one before
        self.longest_stall = 0.0
        #: a step this long after the one before (s) means the emulator was not scheduled: the wheels
        #: run on only this long into the gap, then stand until now (:meth:`BaseFirmware.skip`), and
        #: the frames found waiting arrive now.  None: the frames are spread over the gap
        #: (:func:`arrival_times`) and the motors run on through it
        self.stall_stop = stall_stop
        self.stall_stops = 0            # stalls that stopped turning wheels
        #: called at the end of every step, under :attr:`lock`, with the step's time (what the
        #: firmware's state is valid for): where a world takes the wheels' speeds
        self.on_step = on_step

    # -- public ------------------------------------------------------------
    @property
    def device(self) -> str:
        """Path the host opens for the base."""
        return self._base.pty.link

    @property
    def gripper_device(self) -> str | None:
        return self._grip.pty.link if self._grip else None

    def _endpoints(self) -> list[_Endpoint]:
        return [e for e in (self._base, self._grip) if e is not None]

    def start(self) -> RobotinoEmulator:
        for ep in self._endpoints():
            ep.pty.open()
        if self.faults.close_every > 0:
            self._next_close = self.clock.now() + self.faults.close_every
        self._thread = threading.Thread(target=self._run, name="robotino-emulator", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for ep in self._endpoints():
            ep.pty.close()
        if self._own_dir:
            shutil.rmtree(self.link_dir, ignore_errors=True)

    def __enter__(self) -> RobotinoEmulator:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def close_port(self, duration: float = 0.5, which: str = "base") -> None:
        """Unplug ``which`` ("base", "gripper" or "all") for ``duration`` s."""
        until = self.clock.now() + duration
        with self.lock:
            for ep in self._endpoints():
                if which in ("all", ep.name):
                    ep.closed_until = until

    def set_silent(self, silent: bool) -> None:
        """A hung base: ignore all input and send nothing while set."""
        with self.lock:
            self.silent = silent

    def ground_truth(self) -> tuple[float, float, float]:
        """World pose (x m, y m, theta rad) integrated from the wheels."""
        with self.lock:
            self.firmware.advance(self.clock.now())
            return tuple(self.firmware.pose)  # type: ignore[return-value]

    def setpoints(self) -> tuple[int, int, int, int]:
        with self.lock:
            return tuple(m.setpoint for m in self.firmware.motors)  # type: ignore[return-value]

    def wheel_speeds(self) -> tuple[float, float, float, float]:
        """Actual motor speeds (rpm) now."""
        with self.lock:
            self.firmware.advance(self.clock.now())
            return tuple(m.ss for m in self.firmware.motors)  # type: ignore[return-value]

    def received_setpoints(self) -> list[tuple[float, int, int]]:
        """(time s, motor, rpm) of every SET_MOTOR_SPEED received."""
        with self.lock:
            return list(self.firmware.setpoint_log)

    @property
    def last_step(self) -> float | None:
        """The time of the latest step (the firmware's state is valid for it); None before the first."""
        return self._last_read

    @property
    def watchdog_trips(self) -> int:
        with self.lock:
            return self.firmware.watchdog_trips

    def inject(self, data: bytes, which: str = "base") -> None:
        """Send raw bytes to the host (test hook: partial frames, bad lines)."""
        with self.lock:
            ep = self._base if which == "base" else self._grip
            if ep is not None and ep.pty.is_open:
                ep.pty.write(data)

    def fail_gripper(self, message: str) -> None:
        """Put the gripper into its error state."""
        with self.lock:
            if self.gripper is not None and self._grip is not None:
                now = self.clock.now()
                self._grip.send(self.gripper.fail(message, now), now)

    def stats(self) -> dict:
        with self.lock:
            fw = self.firmware
            out = {"frames": fw.rx_counter, "replies": fw.replies,
                   "checksum_errors": fw.decoder.checksum_errors,
                   "watchdog_trips": fw.watchdog_trips,
                   "watchdog_motion_stops": fw.watchdog_motion_stops,
                   "corrupted": self._base.rx.corrupted + self._base.tx.corrupted,
                   "dropped": self._base.rx.dropped + self._base.tx.dropped,
                   "connects": self._base.connects,
                   "emulator_stalls": self.stalls, "longest_stall_s": round(self.longest_stall, 3),
                   "stall_stops": self.stall_stops}
            if self._grip is not None:
                out["gripper_connects"] = self._grip.connects
            return out

    # -- the loop -------------------------------------------------------------
    def _run(self) -> None:
        poller_timeout_ms = max(1, int(self.idle_period * 1000))
        while not self._stop.is_set():
            try:
                self._step(poller_timeout_ms)
            except Exception:  # keep the emulator alive for the host's sake
                log.exception("emulator step failed")
                self._stop.wait(0.05)

    def _step(self, timeout_ms: int) -> None:
        now = self.clock.now()
        with self.lock:
            self._port_faults(now)
            for ep in self._endpoints():
                self._track_connection(ep, now)
        poller = select.poll()
        fds = {}
        for ep in self._endpoints():
            if ep.pty.is_open and ep.pty.connected:
                poller.register(ep.pty.master, select.POLLIN | (select.POLLOUT if ep.pty.pending else 0))
                fds[ep.pty.master] = ep
        due = [d for d in (ep.next_due() for ep in self._endpoints()) if d is not None]
        if due:
            timeout_ms = max(0, min(timeout_ms, int((min(due) - now) * 1000) + 1))
        events = poller.poll(timeout_ms)
        now = self.clock.now()
        with self.lock:
            last, self._last_read = self._last_read, now
            if last is not None and now - last > self.stall_threshold:
                self.stalls += 1
                self.longest_stall = max(self.longest_stall, now - last)
            stalled = self.stall_stop is not None and last is not None and now - last > self.stall_stop
            if stalled:
                self.firmware.advance(last + self.stall_stop)
                if any(m.ss for m in self.firmware.motors[:3]):
                    self.stall_stops += 1
                self.firmware.skip(now)
            for fd, ev in events:
                ep = fds[fd]
                if ev & select.POLLHUP and not ev & select.POLLIN:
                    ep.pty.hung_up()
                    continue
                data = ep.pty.read()
                if data:
                    ep.bytes_in += len(data)
                    data = ep.rx.apply(data)
                    if ep is self._base and not stalled:
                        for when, chunk in arrival_times(data, last, now, self.host_spacing):
                            self._deliver(ep, chunk, when)
                    else:
                        self._deliver(ep, data, now)
            self.firmware.advance(now)
            if not self.silent:
                reply = self.firmware.take_reply()
                if reply:
                    self._base.send(reply, now)
            if self.gripper is not None and self._grip is not None:
                self._grip.send(self.gripper.advance(now), now)
            for ep in self._endpoints():
                ep.flush(now)
            if self.on_step is not None:
                self.on_step(now)

    def _deliver(self, ep: _Endpoint, data: bytes, now: float) -> None:
        if ep is self._base:
            if not self.silent:
                self.firmware.receive(data, now)
        elif self.gripper is not None:
            ep.send(self.gripper.receive(data, now), now)

    def _track_connection(self, ep: _Endpoint, now: float) -> None:
        if not ep.pty.is_open or ep.pty.connected:
            return          # a connected host's close shows as POLLHUP in the step's poll
        ep.pty.connected = ep.pty.poll_connected()
        if ep.pty.connected:
            ep.connects += 1
            log.info("%s: host opened %s", ep.name, ep.pty.link)
            if ep is self._grip and self.gripper is not None:
                ep.send(self.gripper.reset(now), now)

    def _port_faults(self, now: float) -> None:
        if self._next_close is not None and now >= self._next_close:
            self._next_close = now + self.faults.close_every + self.faults.closed_for
            for ep in self._endpoints():
                ep.closed_until = now + self.faults.closed_for
        for ep in self._endpoints():
            if ep.closed_until is None:
                continue
            if ep.pty.is_open and now < ep.closed_until:
                log.info("%s: closing %s for a fault", ep.name, ep.pty.link)
                ep.pty.close()
                ep.queue.clear()
            elif not ep.pty.is_open and now >= ep.closed_until:
                ep.closed_until = None
                ep.pty.open()
                log.info("%s: reopened %s", ep.name, ep.pty.link)
