"""From camera detections to machine observations.

:class:`SightingCollector` reads ``ctx.tags.detections()`` (oracle or a
perception source), feeds every tag to perception's
:class:`~skills.perception.tags.MachineTracker` with the robot's pose and
its uncertainty, counts the light states reported for each station, and
publishes a :class:`~skills.machines.MachineObservation` per updated
station through ``ctx.machines.observe`` (the agent forwards those to the
team server).  With ``confirm_confidence`` set, a station whose estimate
becomes that confident is also put into the robot's map.
"""
from __future__ import annotations

from collections import Counter

from rll_bt.backend import Pose2D

from ..machines import MachineObservation
from ..perception.tags import MachineTracker


class SightingCollector:
    def __init__(self, ctx, confirm_confidence: float | None = None, min_light_votes: int = 3):
        self.ctx = ctx
        self.tracker = MachineTracker(ctx.profile)
        self.lights: dict[str, Counter] = {}
        self.confirm_confidence = confirm_confidence
        self.min_light_votes = min_light_votes
        self._last_stamp = None

    def look(self) -> set[str]:
        """Process the latest detections once; returns the machines updated."""
        dets = self.ctx.tags.detections()
        if dets is None or dets.stamp == self._last_stamp:
            return set()
        self._last_stamp = dets.stamp
        pose = self.ctx.pose()
        est = self.ctx.estimate()
        sigma = est.std_xy if est is not None else 0.0
        updated: set[str] = set()
        for det in dets.tags:
            machine = self.tracker.add(det, dets.extrinsics, pose, robot_sigma=sigma)
            if machine is not None:
                updated.add(machine)
        for light in dets.lights:
            owner = self.ctx.profile.machine_for_tag(light.tag_id) if light.tag_id is not None else None
            if owner is not None:
                self.lights.setdefault(owner[0], Counter())[light.state] += 1
                updated.add(owner[0])
        for machine in sorted(updated):      # a set: its order changes with the hash seed
            obs = self.observation(machine, dets.stamp)
            if obs is None:
                continue
            self.ctx.machines.observe(obs)
            if (self.confirm_confidence is not None and obs.pose is not None
                    and obs.confidence >= self.confirm_confidence and machine not in self.ctx.machines):
                self.ctx.machines.set(machine, obs.pose)
        return updated

    def light_state(self, machine: str) -> int | None:
        """The most frequent light state seen (0..7), once it has
        ``min_light_votes`` votes."""
        votes = self.lights.get(machine)
        if not votes:
            return None
        state, n = votes.most_common(1)[0]
        return state if n >= self.min_light_votes else None

    def observation(self, machine: str, stamp: float) -> MachineObservation | None:
        est = self.tracker.estimate(machine)
        light = self.light_state(machine)
        if est is None and light is None:
            return None
        pose: Pose2D | None = est.pose if est is not None else None
        side = next(iter(sorted(est.sides)), None) if est is not None else None
        tag = next(iter(sorted(est.tag_ids)), None) if est is not None else None
        return MachineObservation(machine, pose, stamp, side, tag,
                                  est.zone if est is not None else None, light,
                                  est.confidence if est is not None else 0.0)

    def machines_in_zone(self, zone: int, min_confidence: float = 0.3) -> list[str]:
        out = []
        for name, est in self.tracker.estimates().items():
            if est is not None and est.zone == zone and est.confidence >= min_confidence:
                out.append(name)
        return sorted(out)
