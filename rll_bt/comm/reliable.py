"""Acknowledged, repeated delivery of chosen messages, by id, over any link.

TCP loses nothing while it is up, but a radio link drops (a cut, a timeout,
a reconnect) and whatever was on the way is gone.  The messages that must
arrive exactly once in effect (a task, a cancel, a task's final result) go
through a :class:`Reliable` end on each side:

- the sender keeps each such message until the other side acknowledges it,
  and repeats it meanwhile, and at once when the link comes back
  (:meth:`Reliable.resend_now`): first after twice the round trip measured
  on that link (as TCP does, from messages acknowledged at the first send;
  at least ``retry`` s), then doubling up to ``retry_max``;
- the receiver answers every copy with an acknowledgement (``LinkAck``, which
  names the message by its protobuf_comm header and id) and acts on the first
  copy only (:meth:`Reliable.received` says whether a copy is new).

Which messages, and what their id is, is one table (:data:`TEAM_IDS`): a
message type -> a function giving its id, or None for a copy that needs no
delivery.  The task protocol is the league's ``AgentTask`` (one message type
for a task, its cancel, a pause and the result echoed back), so its id is
the task's (assignment's) id with what the copy says in the low three bits
(:func:`agent_task_id`).  Everything is bounded: ``max_pending`` messages
waiting per destination (the oldest is given up and counted), ``remember``
ids per source for spotting repeats.
"""
from __future__ import annotations

from collections import Counter, OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass

from .registry import require_comp_type

#: what an AgentTask says, the low three bits of its id on the link
AT_TASK, AT_CANCEL, AT_PAUSE, AT_RESUME, AT_SUCCEEDED, AT_FAILED, AT_CANCELLED = range(7)


def agent_task_what(m) -> int:
    """What AgentTask ``m`` says: a task, its cancel, a pause or resume, or a
    final result (the task echoed with ``successful`` / ``canceled``)."""
    if m.HasField("successful") or m.HasField("canceled"):
        return AT_CANCELLED if m.canceled else AT_SUCCEEDED if m.successful else AT_FAILED
    if m.cancel_task:
        return AT_CANCEL
    if m.HasField("pause_task"):
        return AT_PAUSE if m.pause_task else AT_RESUME
    return AT_TASK


def agent_task_id(m) -> int:
    """The link's id of AgentTask ``m``: ``task_id << 3 | what`` (:func:`agent_task_what`)."""
    return (int(m.task_id) << 3) | agent_task_what(m)


#: message name -> its id for the link (None: this copy is not delivered reliably)
TEAM_IDS: dict[str, Callable[[object], int | None]] = {"AgentTask": agent_task_id}

Key = tuple[int, int, int]          # (comp_id, msg_type, id)


@dataclass
class _Pending:
    msg: object
    due: float
    wait: float
    sends: int = 1
    sent: float = 0.0


class Reliable:
    """One end's reliable deliveries: what it waits to have acknowledged (per
    destination) and what it owes acknowledgements for (per source).
    Destinations and sources are whatever the caller names peers by (a robot
    number); ``ids``: :data:`TEAM_IDS` or another table."""

    def __init__(self, clock, *, ids: dict[str, Callable] | None = None, retry: float = 1.0,
                 retry_max: float = 8.0, max_pending: int = 256, remember: int = 1024):
        self.clock = clock
        self.ids = TEAM_IDS if ids is None else ids
        self.retry = retry
        self.retry_max = retry_max
        self.max_pending = max_pending
        self.remember = remember
        self._pending: dict[Hashable, OrderedDict[Key, _Pending]] = {}
        self._seen: dict[Hashable, OrderedDict[Key, None]] = {}
        self._owed: dict[Hashable, list[Key]] = {}
        self.rtt: dict[Hashable, float] = {}         # smoothed round trip per destination
        self.counts: Counter[str] = Counter()

    # -- which messages ---------------------------------------------------------------
    def key(self, msg) -> Key | None:
        """The link's name of ``msg``, or None if it is not delivered reliably."""
        f = self.ids.get(msg.DESCRIPTOR.name)
        if f is None:
            return None
        i = f(msg)
        if i is None:
            return None
        comp, mtype = require_comp_type(msg)
        return comp, mtype, int(i)

    # -- sending ------------------------------------------------------------------------
    def track(self, dest: Hashable, msg) -> bool:
        """Keep ``msg`` (just sent, or not sendable now) until ``dest`` acknowledges
        it; whether it is one the link delivers reliably."""
        key = self.key(msg)
        if key is None:
            return False
        box = self._pending.setdefault(dest, OrderedDict())
        old = box.pop(key, None)
        now, wait = self.clock.now(), self.first_wait(dest)
        box[key] = _Pending(msg, now + wait, wait, 1 + (old.sends if old else 0), now)
        self.counts["tracked"] += 1
        while len(box) > self.max_pending:
            box.popitem(last=False)
            self.counts["given_up"] += 1
        return True

    def first_wait(self, dest: Hashable) -> float:
        """Seconds before the first repeat to ``dest``: twice its round trip, within bounds."""
        rtt = self.rtt.get(dest)
        return self.retry if rtt is None else min(max(self.retry, 2.0 * rtt), self.retry_max)

    def forget(self, dest: Hashable, keep: Callable[[object], bool]) -> int:
        """Stop repeating the messages to ``dest`` that ``keep(msg)`` rejects
        (superseded: a task cancelled or given to another robot); how many."""
        box = self._pending.get(dest, {})
        gone = [k for k, p in box.items() if not keep(p.msg)]
        for k in gone:
            del box[k]
        self.counts["superseded"] += len(gone)
        return len(gone)

    def due(self, dest: Hashable | None = None) -> list[tuple[Hashable, object]]:
        """(destination, message) to repeat now (of ``dest`` only, if given); each is
        rescheduled with its wait doubled."""
        now = self.clock.now()
        out = []
        for d, box in self._pending.items():
            if dest is not None and d != dest:
                continue
            for p in box.values():
                if p.due <= now:
                    p.wait = min(p.wait * 2, self.retry_max)
                    p.due = now + p.wait
                    p.sends += 1
                    out.append((d, p.msg))
        self.counts["repeated"] += len(out)
        return out

    def resend_now(self, dest: Hashable) -> list[object]:
        """Everything waiting for ``dest`` (its link just came back), oldest first;
        the waits start again from ``retry``."""
        now, wait = self.clock.now(), self.first_wait(dest)
        box = self._pending.get(dest, {})
        for p in box.values():
            p.wait, p.due = wait, now + wait
            p.sends += 1
        self.counts["repeated"] += len(box)
        return [p.msg for p in box.values()]

    def pending(self, dest: Hashable | None = None) -> list[object]:
        if dest is not None:
            return [p.msg for p in self._pending.get(dest, {}).values()]
        return [p.msg for box in self._pending.values() for p in box.values()]

    def on_ack(self, dest: Hashable, ack) -> int:
        """A LinkAck from ``dest``: stop repeating what it names; how many it closed."""
        box = self._pending.get(dest, {})
        n = 0
        for item in ack.items:
            p = box.pop((int(item.comp_id), int(item.msg_type), int(item.id)), None)
            if p is None:
                continue
            n += 1
            old = self.rtt.get(dest)
            if p.sends == 1:             # Karn: only a message sent once tells the round trip
                sample = self.clock.now() - p.sent
                self.rtt[dest] = sample if old is None else 0.875 * old + 0.125 * sample
            else:                        # repeated: keep the wait that was needed (TCP keeps its backoff)
                self.rtt[dest] = max(old or 0.0, p.wait / 2)
        self.counts["acknowledged"] += n
        return n

    # -- receiving ----------------------------------------------------------------------
    def received(self, source: Hashable, msg) -> bool:
        """A message from ``source``: owe it an acknowledgement if it is delivered
        reliably; whether to act on it (False: a repeat of one already acted on)."""
        key = self.key(msg)
        if key is None:
            return True
        self._owed.setdefault(source, []).append(key)
        seen = self._seen.setdefault(source, OrderedDict())
        if key in seen:
            seen.move_to_end(key)
            self.counts["repeats_dropped"] += 1
            return False
        seen[key] = None
        while len(seen) > self.remember:
            seen.popitem(last=False)
        return True

    def acks(self, make_ack: Callable[[Hashable], object]) -> list[tuple[Hashable, object]]:
        """(source, LinkAck) for what is owed; ``make_ack(source)`` gives an empty
        LinkAck for it.  What is returned is no longer owed."""
        out = []
        for source, keys in self._owed.items():
            if not keys:
                continue
            ack = make_ack(source)
            for comp, mtype, i in dict.fromkeys(keys):
                ack.items.add(comp_id=comp, msg_type=mtype, id=i)
            out.append((source, ack))
        self._owed.clear()
        self.counts["acks_sent"] += len(out)
        return out
