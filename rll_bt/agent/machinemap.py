"""The team server's machine map on the robot.

The server sends ``MachineMap`` on (re)connect and whenever it changes.
The agent keeps it as :class:`KnownMachines` in the run context's services
under ``"machine_map"`` and hands it to every service that wants it
(:func:`distribute`): a service with ``apply_machine_map(known)`` gets the
whole map; one with ``machines.set(name, pose)`` (the skills' context) or
``set(name, pose)`` plus ``subscribe`` (the skills' machine map itself)
gets each station's pose, so navigation and localisation use it at once.
Poses are station centres in the field frame (m, rad).
"""
from __future__ import annotations

import logging
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from ..backend import Pose2D, wrap_angle

log = logging.getLogger("rll_bt.agent")

SERVICE = "machine_map"


@dataclass(frozen=True)
class KnownMachine:
    name: str
    type: str | None = None
    team_color: str | None = None     # "CYAN" / "MAGENTA"
    pose: Pose2D | None = None
    zone: int | None = None
    rotation: int | None = None       # degrees
    input_tag: int | None = None
    output_tag: int | None = None
    confidence: float = 0.0


class KnownMachines(Mapping[str, KnownMachine]):
    """Machine name -> :class:`KnownMachine`, with the map's profile and stamp."""

    def __init__(self, machines: dict[str, KnownMachine] | None = None, profile: str = "", stamp: float = 0.0,
                 received: float = 0.0):
        self._m = dict(machines or {})
        self.profile = profile
        self.stamp = stamp          # server clock
        self.received = received    # agent clock
        self.updates = 0

    @classmethod
    def from_message(cls, msg, received: float = 0.0) -> KnownMachines:
        out: dict[str, KnownMachine] = {}
        for k in msg.machines:
            def opt(field: str, k=k):
                return getattr(k, field) if k.HasField(field) else None
            pose = Pose2D(k.pose.x, k.pose.y, k.pose.theta) if k.HasField("pose") else None
            color = ("CYAN", "MAGENTA")[k.team_color] if k.HasField("team_color") else None
            out[k.name] = KnownMachine(k.name, opt("type"), color, pose, opt("zone"), opt("rotation"),
                                       opt("input_tag"), opt("output_tag"), float(k.confidence))
        return cls(out, msg.profile, msg.stamp, received)

    def __getitem__(self, name: str) -> KnownMachine:
        return self._m[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._m)

    def __len__(self) -> int:
        return len(self._m)

    def pose(self, name: str) -> Pose2D | None:
        m = self._m.get(name)
        return m.pose if m is not None else None

    def __repr__(self) -> str:
        return f"KnownMachines({sorted(self._m)}, profile={self.profile!r})"


def _pose_setter(service: Any):
    """A ``set(name, pose)`` of a service that stores station poses, or None."""
    apply = getattr(service, "apply_machine_map", None)
    if callable(apply):
        return None
    inner = getattr(service, "machines", None)
    if inner is not None and callable(getattr(inner, "set", None)) and not isinstance(inner, Mapping):
        return inner.set
    if callable(getattr(service, "set", None)) and callable(getattr(service, "subscribe", None)):
        return service.set
    return None


def changed_names(old: KnownMachines | None, new: KnownMachines, tolerance: float = 0.01) -> set[str]:
    """Stations whose pose is new or moved by more than ``tolerance`` (m or rad)."""
    out = set()
    for name, m in new.items():
        before = old.get(name) if old is not None else None
        if m.pose is None:
            continue
        p = before.pose if before is not None else None
        if p is None or p.distance_to(m.pose) > tolerance or abs(wrap_angle(p.theta - m.pose.theta)) > tolerance:
            out.add(name)
    return out


def distribute(services: dict[str, Any], known: KnownMachines, names: set[str] | None = None) -> int:
    """Store ``known`` as ``services["machine_map"]`` and pass it on to every
    service that takes it (station poses: only those in ``names`` when
    given, so unchanged stations do not make the skills rebuild their
    maps); returns how many services took it."""
    services[SERVICE] = known
    took = 0
    for name, svc in list(services.items()):
        if svc is known:
            continue
        try:
            apply = getattr(svc, "apply_machine_map", None)
            if callable(apply):
                apply(known)
                took += 1
                continue
            setter = _pose_setter(svc)
            if setter is None:
                continue
            for m in known.values():
                if m.pose is not None and (names is None or m.name in names):
                    setter(m.name, m.pose)
            took += 1
        except Exception:   # a service that chokes on the map must not stop the agent
            log.exception("service %r could not take the machine map", name)
    return took
