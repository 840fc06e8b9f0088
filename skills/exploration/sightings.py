"""From camera detections to machine observations.

:class:`SightingCollector` reads ``ctx.tags.detections()`` (oracle or a
perception source), feeds every tag to perception's
:class:`~skills.perception.tags.MachineTracker` with the robot's pose and
its uncertainty, keeps the light states read for each station, and
publishes a :class:`~skills.machines.MachineObservation` per updated
station through ``ctx.machines.observe`` (the agent forwards those to the
team server).  With ``confirm_confidence`` set, a station whose estimate
becomes that confident is also put into the robot's map.

A station's light state is told only when its readings agree: of the
readings of the last :data:`LIGHT_WINDOW` seconds, at least
``min_light_votes`` and a :data:`LIGHT_SHARE` of them name it, over at
least :data:`LIGHT_SPAN` seconds (read again after a moment, not one
frame counted thrice).  Readings that disagree tell nothing; the
exploration then reads the light from another side
(:class:`~.explore.ExploreZone`), and the old readings leave the window.
(The reader itself reports no reading below its confidence:
``skills.perception.light.reader``.)  A reading handed over as exact (no
class probabilities: oracle perception, which reads the refbox's state)
cannot disagree with itself: those count as before, the most frequent
state once it has ``min_light_votes``.
"""
from __future__ import annotations

from collections import Counter, deque

from rll_bt.backend import Pose2D

from ..machines import MachineObservation
from ..perception.tags import MachineTracker

#: seconds a light reading votes for
LIGHT_WINDOW = 8.0
#: share of the readings in the window a light state needs
LIGHT_SHARE = 0.8
#: seconds between the first and the last reading of that state in the window
LIGHT_SPAN = 0.35


class SightingCollector:
    def __init__(self, ctx, confirm_confidence: float | None = None, min_light_votes: int = 3):
        self.ctx = ctx
        self.tracker = MachineTracker(ctx.profile)
        self.lights: dict[str, deque] = {}           # station -> (stamp, state) readings of a reader
        self.exact: dict[str, Counter] = {}          # station -> votes of exact readings (oracle)
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
            if owner is None:
                continue
            if light.probabilities:
                self.lights.setdefault(owner[0], deque(maxlen=200)).append((dets.stamp, int(light.state)))
            else:
                self.exact.setdefault(owner[0], Counter())[int(light.state)] += 1
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
        """The light state (0..7) the recent readings agree on (see the module), or None."""
        exact = self.exact.get(machine)
        if exact:
            state, n = exact.most_common(1)[0]
            return state if n >= self.min_light_votes else None
        readings = self.lights.get(machine)
        if not readings:
            return None
        latest = readings[-1][0] if self._last_stamp is None else max(readings[-1][0], self._last_stamp)
        while readings and readings[0][0] < latest - LIGHT_WINDOW:
            readings.popleft()
        votes = Counter(state for _, state in readings)
        if not votes:
            return None
        state, n = votes.most_common(1)[0]
        stamps = [t for t, s in readings if s == state]
        if n < self.min_light_votes or n < LIGHT_SHARE * len(readings) or stamps[-1] - stamps[0] < LIGHT_SPAN:
            return None
        return state

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
