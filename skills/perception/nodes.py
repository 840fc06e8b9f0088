"""Perception as behaviour-tree node types, registered through the
``rll_bt.nodes`` entry point ``perception = "skills.perception.nodes:register"``.

All use the ``perception`` service, a :class:`~.service.PerceptionService`.
Without one in ``RunContext.services``, :func:`perception_service` builds it
from the run context: the detections source by the setting
``services["perception_mode"]`` or ``task["perception_mode"]`` ("auto":
the backend's oracle when it has ``DETECTIONS``, the detectors otherwise;
"oracle"; "camera"), the robot pose and the station sink from the ``skills``
service (:class:`~skills.context.SkillContext`).

- ``perceive``: keeps perception running (in a parallel branch while
  exploring): RUNNING for ``duration`` seconds (0: for ever), then SUCCESS.
- ``detect_machine``: SUCCESS once a station (a given one, or any) is
  estimated with at least ``min_confidence``; writes its name, pose, zone,
  rotation and confidence.  MACHINE_NOT_FOUND after ``timeout``.
- ``read_light``: watches a station's signal tower (found through its tag,
  or any tower when ``machine`` is empty) until every light is ON, OFF or
  BLINK; writes the pattern and, when steady, the state 0..7.
  MACHINE_NOT_FOUND after ``timeout``.
"""
from __future__ import annotations

import logging

from py_trees.common import Status as TreeStatus

from rll_bt import rules
from rll_bt.backend import Pose2D
from rll_bt.tree import Input, Node, Output, register_service, write_error

from .service import UNASSIGNED, PerceptionService
from .source import make_tag_source

log = logging.getLogger(__name__)

NOT_FOUND = "MACHINE_NOT_FOUND"


def perception_service(run_ctx) -> PerceptionService:
    """Build the ``perception`` service from a run context (see the module doc)."""
    if run_ctx.backend is None:
        raise RuntimeError("perception needs a robot backend in the run context")
    services, task = run_ctx.services, run_ctx.task
    mode = services.get("perception_mode") or task.get("perception_mode") or "auto"
    sctx = run_ctx.service("skills") if run_ctx.has_service("skills") else None
    if sctx is not None:
        profile = sctx.profile

        def pose():
            sctx.update()
            return sctx.pose_source.pose()

        def sigma():
            est = sctx.estimate()
            return est.std_xy if est is not None else 0.0
        sink = sctx.machines.observe
    else:
        prof = services.get("profile") or task.get("profile") or rules.DEFAULT
        profile = prof if isinstance(prof, rules.Profile) else rules.profile(str(prof))
        pose, sigma, sink = (lambda: None), None, None
    source = make_tag_source(run_ctx.backend, profile, mode)
    return PerceptionService(source, profile, pose, sink, sigma)


class _PerceptionNode(Node):
    requires_services = ("perception",)

    @property
    def service(self) -> PerceptionService:
        return self.ctx.service("perception")

    def initialise(self) -> None:
        self.started = self.ctx.clock.now()

    def elapsed(self) -> float:
        return self.ctx.clock.now() - self.started

    def fail(self, message: str) -> TreeStatus:
        write_error(self._bb, NOT_FOUND, message, self.name)
        self.feedback_message = f"{NOT_FOUND}: {message}"
        return TreeStatus.FAILURE


class Perceive(_PerceptionNode):
    """Keep perception running: every tick, read the camera (or the backend's
    detections) and update the station estimates and light filters, feeding
    machine observations.  RUNNING for ``duration`` seconds (0: for ever),
    then SUCCESS; put it in a parallel branch beside the exploration."""
    preempts = False
    duration = Input(float, "seconds to run; 0 runs until halted", default=0.0)
    machines = Output(list, "names of the stations estimated so far")

    def update(self) -> TreeStatus:
        svc = self.service
        svc.update()
        self.machines = sorted(svc.tracker.tracks)
        if self.duration > 0 and self.elapsed() >= self.duration:
            return TreeStatus.SUCCESS
        return TreeStatus.RUNNING


class DetectMachine(_PerceptionNode):
    """Look at the station tags in view until a station (``machine``, or any
    when empty) is estimated with at least ``min_confidence``; write its
    name, centre pose (field frame), zone, rotation (degrees, the profile's
    steps) and confidence.  Fails with MACHINE_NOT_FOUND after ``timeout``."""
    machine = Input(str, "station name, e.g. C-BS; empty for any", default="")
    min_confidence = Input(float, "0..1", default=0.5)
    timeout = Input(float, "seconds", default=5.0)
    found = Output(str, "the station's name")
    pose = Output(Pose2D, "the station's centre in the field frame")
    zone = Output(int, "the zone number it stands in")
    rotation = Output(int, "its rotation in degrees (discrete steps of the profile)")
    confidence = Output(float, "0..1")

    def update(self) -> TreeStatus:
        svc = self.service
        svc.update()
        names = [self.machine] if self.machine else sorted(svc.tracker.tracks)
        best = None
        for name in names:
            est = svc.tracker.estimate(name)
            if est is not None and est.confidence >= self.min_confidence and \
                    (best is None or est.confidence > best.confidence):
                best = est
        if best is not None:
            self.found, self.pose, self.zone = best.machine, best.pose, best.zone
            self.rotation, self.confidence = best.rotation_deg, best.confidence
            return TreeStatus.SUCCESS
        if self.elapsed() >= self.timeout:
            return self.fail(f"no station{' ' + self.machine if self.machine else ''} seen with "
                             f"confidence {self.min_confidence} within {self.timeout:g} s")
        return TreeStatus.RUNNING


class ReadLight(_PerceptionNode):
    """Watch a station's signal tower (found through its tag in view; any
    tower when ``machine`` is empty) until every light reads ON, OFF or
    BLINK over the filter's window; write the pattern and, when no light
    blinks, the state (green 1 + yellow 2 + red 4).  Fails with
    MACHINE_NOT_FOUND after ``timeout``."""
    machine = Input(str, "station name; empty for any tower in view", default="")
    fresh = Input(bool, "forget earlier frames of this tower first", default=True)
    timeout = Input(float, "seconds", default=8.0)
    pattern = Output(dict, "{green, yellow, red}: ON | OFF | BLINK")
    state = Output(int, "0..7 when steady, -1 when a light blinks")

    def initialise(self) -> None:
        super().initialise()
        if self.fresh:
            self.service.reset_lights(self.machine or UNASSIGNED)

    def update(self) -> TreeStatus:
        svc = self.service
        svc.update()
        pattern = svc.pattern(self.machine or UNASSIGNED)
        if not self.machine and not pattern.complete:      # any tower: also those found through tags
            for name in sorted(svc.filters):
                p = svc.pattern(name)
                if p.complete:
                    pattern = p
                    break
        if pattern.complete:
            self.pattern = pattern.as_dict()
            steady = pattern.steady_state
            self.state = -1 if steady is None else steady
            return TreeStatus.SUCCESS
        if self.elapsed() >= self.timeout:
            return self.fail(f"no steady reading of the signal light"
                             f"{' of ' + self.machine if self.machine else ''} within {self.timeout:g} s")
        return TreeStatus.RUNNING


NODE_TYPES = (Perceive, DetectMachine, ReadLight)


def register(registry) -> None:
    """Entry point ``rll_bt.nodes: perception``: the node types and the
    ``perception`` service factory."""
    register_service("perception", perception_service, replace=True)
    for cls in NODE_TYPES:
        registry.register(cls, replace=True)
