"""From camera detections to machine observations.

:class:`SightingCollector` reads ``ctx.tags.detections()`` (oracle or a
perception source), feeds every tag to perception's
:class:`~skills.perception.tags.MachineTracker` with the robot's pose and
its uncertainty, keeps the light states read for each station, and
publishes a :class:`~skills.machines.MachineObservation` per updated
station through ``ctx.machines.observe`` (the agent forwards those to the
team server).  With ``confirm_confidence`` set, a station whose estimate
becomes that confident is also put into the robot's map.

A station's light is read view by view (:mod:`.light_views`): every
reading of a detector carries its confidence, and each view's verdict goes
to the team server with it and the view's number (``light_confidence``,
``light_view``), where the light code is reported only when views agree
(``teamserver.exploration.lights``).  :meth:`SightingCollector.light_state`
is the state once the views settle it by that same rule; a light read but
not settled (:meth:`SightingCollector.light_unsure`) is read again by the
exploration (:class:`~.explore.ExploreZone`).  (The reader itself reports
no reading below its own confidence: ``skills.perception.light.reader``.)
A reading handed over as exact (no class probabilities: oracle perception,
which reads the refbox's state) cannot disagree with itself: those count
as before, the most frequent state once it has ``min_light_votes``.
"""
from __future__ import annotations

from collections import Counter

from rll_bt.backend import Pose2D

from ..machines import MachineObservation
from ..perception.tags import MachineTracker
from .light_views import LIGHT_WINDOW, LightViews

__all__ = ["LIGHT_WINDOW", "SightingCollector"]


class SightingCollector:
    def __init__(self, ctx, confirm_confidence: float | None = None, min_light_votes: int = 3,
                 views: LightViews | None = None):
        self.ctx = ctx
        self.tracker = MachineTracker(ctx.profile)
        self.views = views or LightViews(min_votes=min_light_votes)   # readings of a reader, view by view
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
        at = getattr(self.ctx, "pose_at", None)     # where the robot was when the frame was taken
        pose = at(dets.stamp) if at is not None else self.ctx.pose()
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
                self.views.add(owner[0], dets.stamp, int(light.state), light.probabilities,
                               None if pose is None else (pose.x, pose.y))
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
        """The light state (0..7) the readings settle on (see the module), or None."""
        exact = self.exact.get(machine)
        if exact:
            state, n = exact.most_common(1)[0]
            return state if n >= self.min_light_votes else None
        return self.views.settled(machine)

    def light_unsure(self, machine: str) -> bool:
        """Read by a detector but not settled: worth reading again."""
        return not self.exact.get(machine) and self.views.unsure(machine)

    def observation(self, machine: str, stamp: float) -> MachineObservation | None:
        est = self.tracker.estimate(machine)
        view = None
        if self.exact.get(machine):
            light = self.light_state(machine)
        else:
            view = self.views.latest(machine)          # each view's verdict goes out, the server weighs them
            light = None if view is None else view.state
        if est is None and light is None:
            return None
        pose: Pose2D | None = est.pose if est is not None else None
        side = next(iter(sorted(est.sides)), None) if est is not None else None
        tag = next(iter(sorted(est.tag_ids)), None) if est is not None else None
        return MachineObservation(machine, pose, stamp, side, tag,
                                  est.zone if est is not None else None, light,
                                  est.confidence if est is not None else 0.0,
                                  None if view is None else view.confidence,
                                  None if view is None else view.view)

    def machines_in_zone(self, zone: int, min_confidence: float = 0.3) -> list[str]:
        out = []
        for name, est in self.tracker.estimates().items():
            if est is not None and est.zone == zone and est.confidence >= min_confidence:
                out.append(name)
        return sorted(out)
