"""Perception running continuously: detections -> machine observations.

:class:`PerceptionService` is updated once per tick (``update()``, cheap
when no new frame arrived).  It reads a detections source (the backend's
oracle or :class:`~.source.CameraPerception`, see
:func:`~.source.make_tag_source`), feeds every station tag to a
:class:`~.tags.MachineTracker` with the robot's pose and its uncertainty,
feeds every light detection that belongs to a station (through the tag id
that found it) to that station's :class:`~.light.temporal.LightFilter`,
and hands a :class:`~skills.machines.MachineObservation` per updated
station to ``sink`` (typically ``SkillContext.machines.observe``, which the
agent forwards to the team server).  :meth:`report` gives the richer view:
zone, discrete rotation, light pattern (ON/OFF/BLINK per light) and
confidence.  Times are the detections' stamps (the backend's clock).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rll_bt.backend import Pose2D
from rll_bt.rules import Profile

from ..machines import MachineObservation
from .light.temporal import UNKNOWN, LightFilter, LightPattern
from .tags import MachineTracker

UNASSIGNED = ""        # light detections no tag tied to a station


@dataclass(frozen=True)
class MachineReport:
    machine: str
    pose: Pose2D | None            # machine centre, field frame
    zone: int | None
    rotation_deg: int | None       # in the profile's discrete steps
    confidence: float              # 0..1, from the tracker's covariance and sightings
    pattern: LightPattern          # ON / OFF / BLINK / UNKNOWN per light
    light_state: int | None        # 0..7 when the pattern is steady and known
    stamp: float
    sides: frozenset[str] = frozenset()


class PerceptionService:
    """See the module docstring.  ``pose()`` returns the robot's field pose
    (None while unknown); ``pose_sigma()`` its position standard deviation
    in metres."""

    def __init__(self, source, profile: Profile, pose: Callable[[], Pose2D | None],
                 sink: Callable[[MachineObservation], None] | None = None,
                 pose_sigma: Callable[[], float] | None = None, light_window: float = 2.0,
                 light_min_span: float = 1.2):
        self.source = source
        self.profile = profile
        self.pose = pose
        self.pose_sigma = pose_sigma or (lambda: 0.0)
        self.sink = sink
        self.tracker = MachineTracker(profile)
        self.light_window, self.light_min_span = light_window, light_min_span
        self.filters: dict[str, LightFilter] = {}
        self.last_seen: dict[str, float] = {}
        self._last_stamp: float | None = None
        self.frames = 0

    def _filter(self, key: str) -> LightFilter:
        f = self.filters.get(key)
        if f is None:
            f = self.filters[key] = LightFilter(self.light_window, self.light_min_span)
        return f

    def update(self) -> set[str]:
        """Process the newest detections once; returns the stations updated."""
        dets = self.source.detections()
        if dets is None or dets.stamp == self._last_stamp:
            return set()
        self._last_stamp = dets.stamp
        self.frames += 1
        updated: set[str] = set()
        pose = self.pose()
        if pose is not None:
            sigma = float(self.pose_sigma() or 0.0)
            for tag in dets.tags:
                machine = self.tracker.add(tag, dets.extrinsics, pose, robot_sigma=sigma)
                if machine is not None:
                    updated.add(machine)
        for light in dets.lights:
            owner = self.profile.machine_for_tag(light.tag_id) if light.tag_id is not None else None
            key = owner[0] if owner is not None else UNASSIGNED
            self._filter(key).add(dets.stamp, int(light.state), light.probabilities or None)
            if owner is not None:
                updated.add(key)
        for machine in sorted(updated):      # a set: its order changes with the hash seed
            self.last_seen[machine] = dets.stamp
            if self.sink is not None:
                obs = self.observation(machine)
                if obs is not None:
                    self.sink(obs)
        return updated

    def pattern(self, machine: str = UNASSIGNED) -> LightPattern:
        f = self.filters.get(machine)
        return f.pattern() if f is not None else LightPattern(UNKNOWN, UNKNOWN, UNKNOWN)

    def report(self, machine: str) -> MachineReport | None:
        est = self.tracker.estimate(machine)
        pattern = self.pattern(machine)
        if est is None and machine not in self.filters:
            return None
        stamp = self.last_seen.get(machine, self._last_stamp or 0.0)
        if est is None:
            return MachineReport(machine, None, None, None, 0.0, pattern, pattern.steady_state, stamp)
        return MachineReport(machine, est.pose, est.zone, est.rotation_deg, est.confidence, pattern,
                             pattern.steady_state, stamp, frozenset(est.sides))

    def reports(self) -> dict[str, MachineReport]:
        names = set(self.tracker.tracks) | (set(self.filters) - {UNASSIGNED})
        return {m: r for m in sorted(names) if (r := self.report(m)) is not None}

    def observation(self, machine: str) -> MachineObservation | None:
        r = self.report(machine)
        if r is None:
            return None
        est = self.tracker.estimate(machine)
        side = min(est.sides) if est is not None and est.sides else None
        tag = min(est.tag_ids) if est is not None and est.tag_ids else None
        return MachineObservation(machine, r.pose, r.stamp, side, tag, r.zone, r.light_state, r.confidence)

    def reset_lights(self, machine: str | None = None) -> None:
        """Forget the light history (of one station, or all)."""
        if machine is None:
            self.filters.clear()
        else:
            self.filters.pop(machine, None)
