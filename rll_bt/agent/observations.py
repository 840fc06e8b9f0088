"""The ``observations`` service: what the robot sees of the stations, streamed
to the team server as it changes.

Skills and tree nodes report sightings with :meth:`ObservationFeed.report`
(any object shaped like ``skills.machines.MachineObservation``: ``machine``,
``pose`` (field frame, machine x from output to input), ``stamp``,
``tag_id``, ``zone``, ``light_state`` 0..7 (green 1, yellow 2, red 4),
``confidence`` 0..1, and for a light read by a detector ``light_confidence``
and ``light_view``, the robot's view of the tower it was read from; or a
mapping with those keys; or a team-protocol
``MachineObservation``), or with :meth:`ObservationFeed.machine`.  A finished
zone search is :meth:`ObservationFeed.zone_searched`.  An object with
``subscribe(callback)`` (the skills' machine map) can be attached so its
observations flow in by themselves.

Only changes go out: a station's first sighting, a new zone, light
pattern, light view or type, a pose that moved more than ``pose_tolerance`` metres or
turned more than ``angle_tolerance`` radians (the orientation likewise), or
a confidence that rose by ``confidence_step``.  Sightings with confidence 0
say nothing and are dropped.  The agent drains the queue into the team-server
link on every step; while the link is down the queue keeps the latest
``max_queue`` messages.
"""
from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from .. import msgs
from ..backend import Pose2D, wrap_angle
from ..clock import Clock
from ..rules import Profile


@dataclass(frozen=True)
class _Sent:
    """What the server has been told about one station."""
    pose: Pose2D | None
    zone: int | None
    orientation: int | None
    pattern: int | None
    type: str | None
    confidence: float
    light_view: int | None = None
    light_confidence: float | None = None


def _get(obj: Any, name: str, default: Any = None) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(name, default)
    return getattr(obj, name, default)


def _pose(value: Any) -> Pose2D | None:
    if value is None:
        return None
    if isinstance(value, Pose2D):
        return value
    if isinstance(value, Mapping):
        return Pose2D(float(value.get("x", 0.0)), float(value.get("y", 0.0)), float(value.get("theta", 0.0)))
    if isinstance(value, (tuple, list)) and len(value) == 3:
        return Pose2D(*map(float, value))
    return Pose2D(float(value.x), float(value.y), float(value.theta))


class ObservationFeed:
    """Collects station sightings and queues team-protocol messages for changes."""

    def __init__(self, profile: Profile, clock: Clock, robot_id: int = 0, *, pose_tolerance: float = 0.15,
                 angle_tolerance: float = math.radians(15.0), confidence_step: float = 0.1,
                 max_queue: int = 500):
        self.profile = profile
        self.clock = clock
        self._attached: set[int] = set()        # sources subscribed to (:meth:`attach_services`)
        self.robot_id = robot_id
        self.pose_tolerance = pose_tolerance
        self.angle_tolerance = angle_tolerance
        self.confidence_step = confidence_step
        self.ms = msgs.message_set("team")
        self._queue: deque = deque(maxlen=max_queue)
        self._sent: dict[str, _Sent] = {}
        self._zones: dict[str, int] = {}          # station -> zone it was last seen in
        self.searched: set[int] = set()            # zones reported searched
        self.reported = 0                          # sightings reported
        self.queued = 0                            # messages queued

    # -- input -------------------------------------------------------------------
    def attach(self, source: Any) -> bool:
        """Subscribe to ``source.subscribe(callback)`` (e.g. the skills' machine map)."""
        sub = getattr(source, "subscribe", None)
        if not callable(sub):
            return False
        sub(self.report)
        return True

    def attach_services(self, services) -> None:
        """:meth:`attach` every service (and its ``machines``) that publishes sightings,
        each once."""
        for svc in list(services):
            for src in (svc, getattr(svc, "machines", None)):
                if src is not None and src is not self and id(src) not in self._attached and self.attach(src):
                    self._attached.add(id(src))

    def report(self, obs: Any) -> bool:
        """Report one sighting; True if it changed what the server knows (a
        message was queued)."""
        if isinstance(obs, self.ms.MachineObservation):
            return self._report_message(obs)
        name = _get(obs, "machine") or _get(obs, "name")
        lights = _get(obs, "light_state", _get(obs, "lights"))
        return self.machine(name, pose=_pose(_get(obs, "pose")), zone=_get(obs, "zone"),
                            orientation=_get(obs, "orientation"), lights=lights, type=_get(obs, "type"),
                            tag_id=_get(obs, "tag_id"), confidence=float(_get(obs, "confidence", 1.0) or 0.0),
                            stamp=_get(obs, "stamp"), covariance=_get(obs, "covariance"),
                            light_confidence=_get(obs, "light_confidence"), light_view=_get(obs, "light_view"))

    def machine(self, name: str | None, *, pose: Pose2D | None = None, zone: int | None = None,
                orientation: int | None = None, lights: int | None = None, type: str | None = None,
                tag_id: int | None = None, confidence: float = 1.0, stamp: float | None = None,
                covariance: Iterable[float] | None = None, light_confidence: float | None = None,
                light_view: int | None = None) -> bool:
        """Report station ``name`` (or, without a name, the station of ``tag_id``).
        ``lights`` goes out with ``light_confidence`` (default ``confidence``)
        and ``light_view`` (the robot's view of the tower it was read from)."""
        self.reported += 1
        if not name and tag_id is not None:
            hit = self.profile.machine_for_tag(int(tag_id))
            name = hit[0] if hit else None
        if not name:
            return False
        if zone is not None and int(zone) <= 0:       # 0: unknown (no profile numbers a zone 0)
            zone = None
        if zone is None and pose is not None:
            zone = self.profile.zone_at(pose.x, pose.y)
        if orientation is None and pose is not None:
            orientation = int(round(math.degrees(pose.theta))) % 360
        conf = max(0.0, min(1.0, float(confidence)))
        if conf <= 0.0 and (lights is None or not light_confidence):      # says nothing
            return False
        new = _Sent(pose, None if zone is None else int(zone), None if orientation is None else int(orientation),
                    None if lights is None else int(lights), type, conf,
                    None if lights is None or light_view is None else int(light_view),
                    None if lights is None or light_confidence is None else float(light_confidence))
        if not self._changed(self._sent.get(name), new):
            return False
        self._sent[name] = self._merge(self._sent.get(name), new)
        if new.zone is not None:
            self._zones[name] = new.zone
        m = self.ms.MachineObservation(robot_id=self.robot_id, stamp=self.clock.now() if stamp is None else stamp)
        m.name.value, m.name.confidence = name, conf
        if tag_id is not None:
            m.tag_id.value, m.tag_id.confidence = int(tag_id), conf
        if pose is not None:
            m.pose.pose.x, m.pose.pose.y, m.pose.pose.theta = pose.x, pose.y, pose.theta
            m.pose.confidence = conf
            if covariance is not None:
                m.pose.covariance.extend(float(c) for c in _flat(covariance))
        if new.zone is not None:
            m.zone.value, m.zone.confidence = new.zone, conf
        if new.orientation is not None:
            m.orientation.value, m.orientation.confidence = new.orientation, conf
        if new.pattern is not None:
            m.lights.pattern = new.pattern & 7
            m.lights.confidence = conf if light_confidence is None else max(0.0, min(1.0, float(light_confidence)))
            if new.light_view is not None:
                m.lights.view = new.light_view
        if type:
            m.type.value, m.type.confidence = str(type), conf
        self._push(m)
        return True

    def zone_searched(self, zone: int, machines: Iterable[str] | None = None, stamp: float | None = None) -> None:
        """A zone has been searched completely; ``machines`` found there
        (None: the stations seen in that zone so far)."""
        zone = int(zone)
        self.searched.add(zone)
        found = sorted(set(self.seen_in_zone(zone) if machines is None else machines))
        now = self.clock.now() if stamp is None else stamp
        if not found:
            self._push(self.ms.MachineObservation(robot_id=self.robot_id, stamp=now, searched_zone=zone,
                                                  seen_in_zone=False))
        self._push(self.ms.ZoneExplored(robot_id=self.robot_id, zone=zone, machines=found, stamp=now))

    def seen_in_zone(self, zone: int) -> list[str]:
        """Stations last seen in ``zone``."""
        return sorted(n for n, z in self._zones.items() if z == int(zone))

    # -- output ------------------------------------------------------------------
    def drain(self) -> list:
        """Queued messages, oldest first (the queue is emptied)."""
        out = list(self._queue)
        self._queue.clear()
        return out

    def requeue(self, messages: list) -> None:
        """Put back messages that could not be sent (at the front)."""
        self._queue.extendleft(reversed(messages))

    def __len__(self) -> int:
        return len(self._queue)

    # -- internals ----------------------------------------------------------------
    def _push(self, m) -> None:
        self._queue.append(m)
        self.queued += 1

    def _report_message(self, m) -> bool:
        if not m.robot_id:
            m.robot_id = self.robot_id
        self.reported += 1
        self._push(m)
        return True

    def _changed(self, old: _Sent | None, new: _Sent) -> bool:
        if old is None:
            return True
        for attr in ("zone", "pattern", "type", "light_view"):
            v = getattr(new, attr)
            if v is not None and v != getattr(old, attr):
                return True
        if new.orientation is not None:
            if old.orientation is None:
                return True
            turned = abs((new.orientation - old.orientation + 180) % 360 - 180)
            if turned > math.degrees(self.angle_tolerance):
                return True
        if new.pose is not None:
            if old.pose is None:
                return True
            if new.pose.distance_to(old.pose) > self.pose_tolerance or \
                    abs(wrap_angle(new.pose.theta - old.pose.theta)) > self.angle_tolerance:
                return True
        if new.light_confidence is not None and (old.light_confidence is None or abs(
                new.light_confidence - old.light_confidence) >= self.confidence_step / 2):
            return True                  # a view's reading became surer (or less sure)
        return new.confidence >= old.confidence + self.confidence_step

    @staticmethod
    def _merge(old: _Sent | None, new: _Sent) -> _Sent:
        if old is None:
            return new
        return _Sent(*(getattr(new, a) if getattr(new, a) is not None else getattr(old, a)
                       for a in ("pose", "zone", "orientation", "pattern", "type")),
                     new.confidence, *((new.light_view, new.light_confidence) if new.pattern is not None
                                       else (old.light_view, old.light_confidence)))


def _flat(values: Iterable) -> list[float]:
    out: list[float] = []
    for v in values:
        if isinstance(v, (list, tuple)) or hasattr(v, "__iter__") and not isinstance(v, (str, bytes)):
            out.extend(_flat(v))
        else:
            out.append(float(v))
    return out
