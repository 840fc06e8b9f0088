"""A lossy radio between a robot and everyone else: faults injected into a transport.

The rulebook warns that communication loss must be expected on the field's
wifi; the strongest team tests with 2 s of delay, 200 ms of jitter and 20 %
packet loss on the robots' traffic (netem on the robot's interface).  A
:class:`FaultyTransport` wraps any :class:`~rll_bt.comm.transport.Transport`
of a robot and applies :class:`LinkFaults` in both directions:

- datagram channels (the refbox's UDP channels, or a bus channel): each frame
  is lost with probability ``loss``, delivered after ``delay`` plus normal
  ``jitter`` (so frames overtake one another), sent ahead of the queue with
  probability ``reorder``, delivered twice with probability ``duplicate``;
- stream channels (the TCP link to the team server): TCP loses nothing, so a
  lost segment costs a retransmission (``rto`` seconds, doubling while losses
  follow one another), and frames stay in order; no duplicates;
- both: a ``bandwidth`` cap in bit/s (frames queue behind each other),
  ``stalls`` (intervals in which the link carries nothing yet loses nothing,
  as in a chain of retransmissions: a frame due inside one arrives at its
  end) and link ``cuts`` (intervals on the transport's clock).  On a datagram channel
  a cut loses what is sent or arrives during it; a stream is *disconnected*
  for the cut (the wrapper reports ``disconnected`` and ``connected`` events,
  sends fail, what was in flight is lost), as a real TCP link times out.

Randomness comes from ``seed`` so a lockstep game stays deterministic for a
seed.  Outgoing frames wait in the wrapper until their time comes: it sends
them from :meth:`send`, :meth:`receive`, :meth:`events` and :meth:`wait`,
which a robot calls every tick.  :attr:`FaultyTransport.counts` tells what
the layer did (sent, lost, duplicated, delayed, cut, overflow: frames beyond
``max_held`` held in one direction, dropped as a full queue drops them).
"""
from __future__ import annotations

import dataclasses
import heapq
import itertools
import random
import re
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from ..clock import Clock, WallClock
from .transport import CONNECTED, DISCONNECTED, LinkEvent, Received

#: frame overhead added to a message's protobuf size (headers, IV and padding)
_OVERHEAD = 8 + 4 + 32


@dataclass(frozen=True)
class LinkFaults:
    """Faults of one link, one way each (applied to what is sent and what arrives).

    ``loss``, ``duplicate``, ``reorder``: probabilities per frame;
    ``delay``, ``jitter``: seconds (jitter is a standard deviation);
    ``bandwidth``: bit/s or None; ``cuts``, ``stalls``: ``(start, end)`` clock times;
    ``rto``: the first retransmission time of a stream frame whose segment was lost.
    """

    loss: float = 0.0
    delay: float = 0.0
    jitter: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    bandwidth: float | None = None
    cuts: tuple[tuple[float, float], ...] = ()
    rto: float = 0.2
    stalls: tuple[tuple[float, float], ...] = ()

    def __post_init__(self):
        for name in ("loss", "duplicate", "reorder"):
            v = getattr(self, name)
            if not 0.0 <= v < 1.0:
                raise ValueError(f"{name} must be in [0, 1), not {v}")
        for name in ("delay", "jitter", "rto"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must not be negative")
        if self.bandwidth is not None and self.bandwidth <= 0:
            raise ValueError("bandwidth must be positive (bit/s)")
        for a, b in self.cuts + self.stalls:
            if b <= a:
                raise ValueError(f"a cut or stall must end after it starts: {a}-{b}")

    @property
    def perfect(self) -> bool:
        return self == LinkFaults(rto=self.rto)

    def cut_at(self, t: float) -> tuple[float, float] | None:
        """The cut that ``t`` falls in, if any."""
        for a, b in self.cuts:
            if a <= t < b:
                return a, b
        return None


_CUT = re.compile(r"^(?P<who>[^:]+):(?P<t0>\d+(\.\d*)?)-(?P<t1>\d+(\.\d*)?)$")


def parse_cut(text: str) -> tuple[str, float, float]:
    """``"R2:300-330"`` -> ``("R2", 300.0, 330.0)``; ValueError names the problem."""
    m = _CUT.match(text.strip())
    if not m:
        raise ValueError(f"a cut is WHO:T0-T1 in seconds (e.g. R2:300-330), not {text!r}")
    t0, t1 = float(m["t0"]), float(m["t1"])
    if t1 <= t0:
        raise ValueError(f"cut {text!r} ends before it starts")
    return m["who"], t0, t1


def robot_matches(who: str, robot: int) -> bool:
    """Whether the cut target ``who`` ("R2", "2", "all", "*") names robot ``robot``."""
    w = who.strip().upper()
    return w in ("ALL", "*") or w == f"R{robot}" or w == str(robot)


@dataclass(frozen=True)
class NetFaults:
    """The faults a game puts on every robot's team-server link (``--net-*``):
    the same loss, delay, jitter and bandwidth for each robot, and cuts of
    named robots (``(who, t0, t1)``, ``who`` as :func:`robot_matches` reads it)."""

    loss: float = 0.0
    delay: float = 0.0
    jitter: float = 0.0
    bandwidth: float | None = None
    cuts: tuple[tuple[str, float, float], ...] = ()

    def __post_init__(self):
        LinkFaults(loss=self.loss, delay=self.delay, jitter=self.jitter, bandwidth=self.bandwidth)  # checks
        for who, _a, _b in self.cuts:
            if not (who.strip().upper() in ("ALL", "*") or re.fullmatch(r"R?\d+", who.strip().upper())):
                raise ValueError(f"a cut names a robot as R<N>, <N> or all, not {who!r}")

    @property
    def perfect(self) -> bool:
        return self == NetFaults()

    def for_robot(self, robot: int, offset: float = 0.0) -> LinkFaults | None:
        """The link faults of robot ``robot`` (None: a perfect link); cut times
        shifted by ``offset`` (the clock's time at the cuts' zero)."""
        cuts = tuple((a + offset, b + offset) for who, a, b in self.cuts if robot_matches(who, robot))
        f = LinkFaults(loss=self.loss, delay=self.delay, jitter=self.jitter, bandwidth=self.bandwidth, cuts=cuts)
        return None if f.perfect else f

    def args(self, robot: int) -> list[str]:
        """``rll-bt agent`` options giving robot ``robot`` these faults."""
        f = self.for_robot(robot)
        if f is None:
            return []
        out = ["--net-loss", repr(f.loss), "--net-delay", repr(f.delay), "--net-jitter", repr(f.jitter)]
        if f.bandwidth is not None:
            out += ["--net-bandwidth", repr(f.bandwidth)]
        for a, b in f.cuts:
            out += ["--net-cut", f"{a:g}-{b:g}"]
        return out


@dataclass(order=True)
class _Held:
    due: float
    order: int
    item: Any = field(compare=False)


class FaultyTransport:
    """``inner`` with ``faults`` applied both ways.  ``stream``: TCP-like semantics
    (see the module docstring); by default taken from the inner transport (a
    transport with ``clients`` or ``connected`` is a stream)."""

    def __init__(self, inner, faults: LinkFaults, *, seed: int | str = 0, clock: Clock | None = None,
                 stream: bool | None = None, max_held: int = 10000):
        self.inner = inner
        self.faults = faults
        self.channel = inner.channel
        self.stats = inner.stats
        self.clock = clock if clock is not None else getattr(inner, "clock", None) or WallClock()
        self.stream = stream if stream is not None else (hasattr(inner, "connected") or hasattr(inner, "clients"))
        self._rng = random.Random(f"{seed}/{self.channel}")
        self._order = itertools.count()
        self._out: list[_Held] = []           # (due, msg, kwargs) to send
        self._in: list[_Held] = []            # Received to deliver
        self._free = {"out": 0.0, "in": 0.0}  # bandwidth: when each direction is free again
        self._last = {"out": 0.0, "in": 0.0}  # streams: in order
        self._rto = {"out": faults.rto, "in": faults.rto}
        self._events: list[LinkEvent] = []
        self.max_held = max_held              # frames held per direction; beyond it the link drops them
        self._in_cut: tuple[float, float] | None = None
        self.counts: Counter[str] = Counter()

    # -- scheduling ------------------------------------------------------------------
    def _schedule(self, way: str, size: int, now: float) -> list[float]:
        """Delivery times for one frame (empty: lost)."""
        f, rng = self.faults, self._rng
        if f.cut_at(now) is not None:
            self.counts[f"cut_{way}"] += 1
            return []
        extra = 0.0
        if rng.random() < f.loss:
            if not self.stream:
                self.counts[f"lost_{way}"] += 1
                return []
            extra = self._rto[way]                  # retransmitted after the timeout
            self._rto[way] = min(self._rto[way] * 2, 8.0)
            self.counts[f"retransmitted_{way}"] += 1
        else:
            self._rto[way] = f.rto
        copies = 2 if (not self.stream and rng.random() < f.duplicate) else 1
        if copies == 2:
            self.counts[f"duplicated_{way}"] += 1
        out = []
        for _ in range(copies):
            ahead = not self.stream and rng.random() < f.reorder
            d = 0.0 if ahead else max(0.0, rng.gauss(f.delay, f.jitter) if f.jitter else f.delay)
            due = now + d + extra
            for a, b in f.stalls:
                if a <= due < b:
                    due = b                         # held up: arrives when the stall ends
            if f.bandwidth is not None:
                start = max(due, self._free[way])
                self._free[way] = start + size * 8.0 / f.bandwidth
                due = self._free[way]
            if self.stream:
                due = max(due, self._last[way])
                self._last[way] = due
            out.append(due)
        if out[0] > now:
            self.counts[f"delayed_{way}"] += 1
        return out

    def _check_cut(self, now: float) -> None:
        cut = self.faults.cut_at(now)
        if cut == self._in_cut:
            return
        if self.stream:
            if self._in_cut is not None:
                self._events.append(LinkEvent(CONNECTED, "fault layer", self.channel, now))
            if cut is not None:
                self._events.append(LinkEvent(DISCONNECTED, "fault layer", self.channel, now))
                self.counts["cut_in"] += len(self._in)
                self.counts["cut_out"] += len(self._out)
                self._in.clear()
                self._out.clear()
        self._in_cut = cut

    def _flush(self) -> None:
        now = self.clock.now()
        self._check_cut(now)
        while self._out and self._out[0].due <= now:
            held = heapq.heappop(self._out)
            msg, kwargs = held.item
            if self.faults.cut_at(now) is not None:
                self.counts["cut_out"] += 1
                continue
            if self.inner.send(msg, **kwargs):
                self.counts["sent"] += 1

    # -- the transport interface ------------------------------------------------------
    def send(self, msg, **kwargs) -> bool:
        self._flush()
        now = self.clock.now()
        if self.stream and self.faults.cut_at(now) is not None:
            self.counts["cut_out"] += 1
            return False
        if self.faults.perfect:
            return self.inner.send(msg, **kwargs)
        for due in self._schedule("out", msg.ByteSize() + _OVERHEAD, now):
            if len(self._out) >= self.max_held:
                self.counts["overflow_out"] += 1
                continue
            heapq.heappush(self._out, _Held(due, next(self._order), (msg, kwargs)))
        self._flush()
        return True

    def receive(self) -> list[Received]:
        self._flush()
        now = self.clock.now()
        for r in self.inner.receive():
            if self.faults.perfect:
                heapq.heappush(self._in, _Held(now, next(self._order), r))
                continue
            for due in self._schedule("in", r.msg.ByteSize() + _OVERHEAD, now):
                if len(self._in) >= self.max_held:
                    self.counts["overflow_in"] += 1
                    continue
                heapq.heappush(self._in, _Held(due, next(self._order), r))
        out = []
        while self._in and self._in[0].due <= now:
            held = heapq.heappop(self._in)
            out.append(dataclasses.replace(held.item, time=max(held.item.time, held.due)))
        return out

    def events(self) -> list[LinkEvent]:
        self._flush()
        inner = self.inner.events()
        if self.faults.cut_at(self.clock.now()) is not None and self.stream:
            inner = []                        # the link is down for the layers above
        out, self._events = self._events + inner, []
        return out

    def wait(self, timeout: float) -> bool:
        self._flush()
        pending = [h.due for h in self._in[:1]] + [h.due for h in self._out[:1]]
        if pending:
            timeout = max(0.0, min(timeout, min(pending) - self.clock.now()))
        got = self.inner.wait(timeout)
        self._flush()
        return got or bool(self._in and self._in[0].due <= self.clock.now())

    @property
    def connected(self) -> bool:
        """A stream client's link is down during a cut."""
        return self.inner.connected and not (self.stream and self.faults.cut_at(self.clock.now()))

    def close(self) -> None:
        self.inner.close()

    def __getattr__(self, name: str):
        # everything else (set_crypto, clients, connected, address...) is the inner transport's
        return getattr(self.inner, name)
