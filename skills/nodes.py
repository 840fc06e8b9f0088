"""The skills as behaviour-tree node types, registered through the
``rll_bt.nodes`` entry point (``skills = "skills.nodes:register"``).

Every action node wraps one :class:`~skills.activity.Activity` and never
blocks a tick: ``initialise`` starts it, ``update`` polls it once,
``terminate`` cancels it when the node is interrupted (which stops the
robot).  On failure a node writes the skill's error code (a name of the
team protocol's ``ErrorCode``) and message to the tree's error keys
(``/error/code``, ``/error/message``) and to its ``error`` output.

All nodes use the ``skills`` service: a :class:`~skills.context.SkillContext`
the agent puts into ``RunContext.services["skills"]``.  Without one (e.g.
``rll-bt tree run``), :func:`skills_service` builds it from the backend and
clock of the run context, the rules profile ``services["profile"]`` or
``task["profile"]`` (default ``rcll2016``) and the start pose
``services["start_pose"]`` or ``task["start_pose"]`` (without a start pose
the robot localises globally); its ``robot_number`` is ``services["robot_number"]``
(the agent's robot id: who gives way first, :mod:`.navigation.yielding`).

Station sides follow the team protocol: ``INPUT``, ``OUTPUT``, ``SHELF``
(with ``shelf_slot`` 0..2) or ``SLIDE``.  Zones are numbers or names of
the profile (``Z9``, ``C_Z12``).
"""
from __future__ import annotations

import logging
import math

from py_trees.common import Status as TreeStatus

from rll_bt import rules
from rll_bt.backend import Capability, Pose2D, wrap_angle
from rll_bt.plugins import offers
from rll_bt.tree import Input, Node, Output, register_service, write_error

from .activity import Activity, Sequence, Status
from .context import SkillContext
from .errors import SkillError
from .exploration import ExploreZone
from .localisation.config import PRESETS
from .localisation.relocalise import Relocalise
from .manipulation import ApproachStation, GrabFrom, PutOnto, place_for
from .manipulation.shelf import GrabFromShelf, shelf_memory
from .manipulation.station import back_off_distance
from .navigation import Navigate, PoseGoal, StationSideGoal, ZoneGoal
from .navigation.motions import LookTurn, MoveRelative, Turn, facing_station, look_angle

log = logging.getLogger(__name__)

SIDES = ("INPUT", "OUTPUT", "SHELF", "SLIDE")


def skills_service(run_ctx) -> SkillContext:
    """Build the ``skills`` service from a run context (see the module doc)."""
    if run_ctx.backend is None:
        raise RuntimeError("the skills need a robot backend in the run context")
    services, task = run_ctx.services, run_ctx.task
    prof = services.get("profile") or task.get("profile") or rules.DEFAULT
    profile = prof if isinstance(prof, rules.Profile) else rules.profile(str(prof))
    start = services.get("start_pose") or task.get("start_pose")
    preset = services.get("localisation") or task.get("localisation") or "standard"
    number = int(services.get("robot_number") or 0)
    if start is None:
        ctx = SkillContext.create(run_ctx.backend, run_ctx.clock, profile, Pose2D(), localisation=preset,
                                  robot_number=number)
        ctx.pose_source.initialise_global()
        log.warning("no start pose given: localising globally")
        return ctx
    start = as_pose(start)
    return SkillContext.create(run_ctx.backend, run_ctx.clock, profile, start, localisation=preset,
                               robot_number=number)


def as_pose(value) -> Pose2D:
    """A pose from a Pose2D, [x, y, theta] or {x:, y:, theta:}."""
    if isinstance(value, Pose2D):
        return value
    if isinstance(value, dict):
        return Pose2D(float(value.get("x", 0.0)), float(value.get("y", 0.0)), float(value.get("theta", 0.0)))
    return Pose2D(*(float(v) for v in value))


def zone_number(profile, zone) -> int:
    """A zone given as a number or a name of the profile."""
    if isinstance(zone, str) and not zone.isdigit():
        return profile.zone_number(zone)
    return int(zone)


class SkillNode(Node):
    """Base of the skill nodes: runs the activity made by ``make``."""

    requires_services = ("skills",)
    error = Output(str, "the error code when the skill failed (a team protocol ErrorCode name)")

    def make(self, sctx: SkillContext) -> Activity:  # pragma: no cover - subclasses
        raise NotImplementedError

    def done(self, activity: Activity) -> None:
        """Write outputs after success (subclasses)."""

    def initialise(self) -> None:
        sctx = self.ctx.service("skills")
        try:
            self.activity = self.make(sctx)
        except Exception as exc:      # bad port values: fail this node, not the tree runner
            self.activity = None
            self._setup_error = str(exc)
            return
        self.activity.start()

    def update(self) -> TreeStatus:
        act = self.activity
        if act is None:
            self._fail(SkillError.INVALID_TASK.value, self._setup_error)
            return TreeStatus.FAILURE
        status = act.poll()
        self.feedback_message = act.message or act.name
        if status is Status.RUNNING:
            return TreeStatus.RUNNING
        if status is Status.SUCCESS:
            self.done(act)
            return TreeStatus.SUCCESS
        self._fail(act.error.value, act.message)
        return TreeStatus.FAILURE

    def _fail(self, code: str, message: str) -> None:
        self.error = code
        write_error(self._bb, code, message, self.name)
        self.feedback_message = f"{code}: {message}"

    def terminate(self, new_status: TreeStatus) -> None:
        act = getattr(self, "activity", None)
        if act is not None and act.status is Status.RUNNING:
            act.cancel()


class NavigateToPose(SkillNode):
    """Drive to a field pose (plan, follow, stop for and replan around
    obstacles).  Fails with NAVIGATION_FAILED, LOCALISATION_LOST or TIMEOUT."""
    goal = Input(Pose2D, "target pose in the field frame {x: m, y: m, theta: rad}")
    position_tolerance = Input(float, "metres", default=0.05)
    heading_tolerance = Input(float, "radians", default=0.05)
    max_speed = Input(float, "m/s, at most the rules' 0.7", default=0.7)
    timeout = Input(float, "seconds; 0 = from the distance", default=0.0)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        return Navigate(sctx, PoseGoal(self.goal), self.position_tolerance, self.heading_tolerance,
                        self.max_speed, self.timeout or None)


class NavigateToZone(SkillNode):
    """Drive to a zone's centre (or the free spot in it nearest the centre)."""
    zone = Input(object, "zone number or name (Z9, C_Z12)")
    timeout = Input(float, "seconds; 0 = from the distance", default=0.0)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        return Navigate(sctx, ZoneGoal(zone_number(sctx.profile, self.zone)), position_tolerance=0.1,
                        timeout=self.timeout or None)


class NavigateToStation(SkillNode):
    """Drive in front of a station side (pose from the machine map), facing it.
    Fails with MACHINE_NOT_FOUND when the station's pose is unknown."""
    machine = Input(str, "station name, e.g. C-BS")
    side = Input(str, "station side", default="OUTPUT", choices=SIDES)
    shelf_slot = Input(int, "shelf slot 0..2 for side SHELF", default=0)
    distance = Input(float, "metres from the robot centre to the face", default=0.62)
    timeout = Input(float, "seconds; 0 = from the distance", default=0.0)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        place = place_for(self.machine, self.side, self.shelf_slot)
        return Navigate(sctx, StationSideGoal(place.machine, place.side, self.distance, place.spot),
                        position_tolerance=0.03, heading_tolerance=0.04, timeout=self.timeout or None)


class ExploreZoneNode(SkillNode):
    """Look for a station in a zone from viewpoints around it; report what is
    seen as machine observations.  SUCCESS also when the zone is empty."""
    node_type = "explore_zone"
    zone = Input(object, "zone number or name")
    viewpoints = Input(list, "optional poses to look from", default=[])
    want_light = Input(bool, "read the light pattern (rcll2016 exploration)", default=True)
    timeout = Input(float, "seconds", default=240.0)
    found = Output(list, "names of the stations seen in the zone")
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        vps = [as_pose(p) for p in (self.viewpoints or [])]
        want = self.want_light and sctx.profile.exploration_reports == "type+zone"
        return ExploreZone(sctx, zone_number(sctx.profile, self.zone), vps or None, want, timeout=self.timeout)

    def done(self, activity):
        self.found = list(activity.found)


class ApproachStationNode(SkillNode):
    """Drive to a station side, line up on its tag and dock by laser, ready
    to grab or put.  Fails with ALIGN_FAILED, MACHINE_NOT_FOUND, NAVIGATION_FAILED."""
    node_type = "approach_station"
    machine = Input(str, "station name, e.g. C-BS")
    side = Input(str, "station side", default="OUTPUT", choices=SIDES)
    shelf_slot = Input(int, "shelf slot 0..2 for side SHELF", default=0)
    timeout = Input(float, "seconds", default=120.0)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER

    def make(self, sctx):
        return ApproachStation(sctx, place_for(self.machine, self.side, self.shelf_slot),
                               timeout=self.timeout)


class Grab(SkillNode):
    """Pick up a workpiece at a station side (OUTPUT, SHELF, INPUT) and check
    that the gripper really holds it: GRAB_FAILED when it does not."""
    machine = Input(str, "station name, e.g. C-BS")
    side = Input(str, "station side", default="OUTPUT", choices=SIDES)
    shelf_slot = Input(int, "shelf slot 0..2 for side SHELF", default=0)
    approach = Input(bool, "drive there and dock first (false: already docked)", default=True)
    timeout = Input(float, "seconds", default=150.0)
    holding = Output(bool, "whether the gripper holds a workpiece afterwards")
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.GRIPPER

    def make(self, sctx):
        self._sctx = sctx
        return GrabFrom(sctx, place_for(self.machine, self.side, self.shelf_slot), self.approach,
                        timeout=self.timeout)

    def done(self, activity):
        self.holding = self._sctx.backend.holding()
        if self.holding and str(self.side).upper() == "SHELF":      # that slot is empty now
            shelf_memory(self._sctx).mark_empty(self.machine, self.shelf_slot)

    def update(self) -> TreeStatus:
        status = super().update()
        if status is TreeStatus.FAILURE and getattr(self, "_sctx", None) is not None:
            self.holding = self._sctx.backend.holding()
        return status


class GrabFromShelfNode(SkillNode):
    """Pick up a workpiece from whichever slot of a cap station's shelf holds
    one (:mod:`.manipulation.shelf`: one grab per slot, slots found empty are
    remembered); GRAB_FAILED "no workpiece found ..." when none does."""
    node_type = "grab_from_shelf"
    machine = Input(str, "a cap station, e.g. C-CS1")
    timeout = Input(float, "seconds", default=400.0)
    slot = Output(int, "the slot taken from")
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.GRIPPER

    def make(self, sctx):
        return GrabFromShelf(sctx, self.machine, timeout=self.timeout)

    def done(self, activity):
        self.slot = activity.slot


class Put(SkillNode):
    """Put the held workpiece onto a station's INPUT conveyor or a ring
    station's SLIDE; PUT_FAILED when the gripper still holds it afterwards."""
    machine = Input(str, "station name, e.g. C-RS1")
    side = Input(str, "station side", default="INPUT", choices=("INPUT", "SLIDE", "OUTPUT", "SHELF"))
    shelf_slot = Input(int, "shelf slot 0..2 for side SHELF", default=0)
    approach = Input(bool, "drive there and dock first (false: already docked)", default=True)
    timeout = Input(float, "seconds", default=150.0)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.GRIPPER

    def make(self, sctx):
        return PutOnto(sctx, place_for(self.machine, self.side, self.shelf_slot), self.approach,
                       timeout=self.timeout)


class BackOff(SkillNode):
    """Back off ``distance`` metres straight back (away from a station).
    The laser does not see behind: the known map limits the way back, and
    the other robots the laser saw there.  In the open (no station ahead,
    where no one keeps the strip behind free) the robot turns until the way
    back lies in the laser's view, moves along it sideways (the base is
    holonomic) while the laser watches it, and turns back: a robot standing
    behind it, or coming up while it backs off, stops it."""
    distance = Input(float, "metres", default=0.35)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        return back_off(sctx, abs(self.distance))


def back_off(sctx, distance: float) -> Activity:
    """The :class:`BackOff` node's activity: ``distance`` metres at most along
    the way straight back.  Facing a station it backs off at once.  In the
    open it turns by :func:`look_angle` first, so that the way back (and the
    strip either side of it) lies in the laser's view, backs off sideways there
    with the live scan guarding the way, then turns back to its heading.
    (Looking behind and turning back before a blind back-off was not enough:
    a robot that came up behind during the turn back was remembered where it
    had been and backed into; issue 20, seed 1 at cd41937, 970.5 s.)"""
    if facing_station(sctx):
        return MoveRelative(sctx, -back_off_distance(sctx, distance), speed=0.2, partial=True)
    heading = sctx.pose().theta
    turn = look_angle(sctx)

    def move():
        way = wrap_angle(heading + math.pi - sctx.pose().theta)     # the way back, in the robot frame of now
        d = back_off_distance(sctx, distance, heading=heading)
        return MoveRelative(sctx, d * math.cos(way), d * math.sin(way), speed=0.2, partial=True)
    return Sequence(sctx, [lambda: LookTurn(sctx, by=turn), move, lambda: LookTurn(sctx, by=-turn)],
                    name="back off")


class TurnNode(SkillNode):
    """Turn on the spot by ``angle`` radians (e.g. 6.28 to look around)."""
    node_type = "turn"
    angle = Input(float, "radians, counter-clockwise positive")
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY

    def make(self, sctx):
        return Turn(sctx, by=self.angle)


class RelocaliseNode(SkillNode):
    """Recover a lost pose: spread the particles around the last estimate
    (or over the field) and turn until confident; LOCALISATION_LOST if not."""
    node_type = "relocalise"
    global_search = Input(bool, "search the whole field instead of around the last pose", default=False)
    requires_capabilities = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER

    def make(self, sctx):
        return Relocalise(sctx, global_search=self.global_search)


class Localised(Node):
    """SUCCESS when the pose confidence is at least ``min_confidence``."""
    kind = "condition"
    requires_services = ("skills",)
    min_confidence = Input(float, "0..1", default=0.5)

    def update(self) -> TreeStatus:
        sctx = self.ctx.service("skills")
        sctx.update()
        ok = sctx.pose_source.confidence >= self.min_confidence and not sctx.pose_source.lost
        return TreeStatus.SUCCESS if ok else TreeStatus.FAILURE


class HoldingWorkpiece(Node):
    """SUCCESS when the gripper holds a workpiece (FAILURE when it does not or cannot tell)."""
    kind = "condition"
    requires_capabilities = Capability.GRIPPER

    def update(self) -> TreeStatus:
        return TreeStatus.SUCCESS if self.ctx.backend.holding() is True else TreeStatus.FAILURE


NODE_TYPES = (NavigateToPose, NavigateToZone, NavigateToStation, ExploreZoneNode, ApproachStationNode,
              Grab, GrabFromShelfNode, Put, BackOff, TurnNode, RelocaliseNode, Localised, HoldingWorkpiece)


@offers(localisation=PRESETS)
def register(registry) -> None:
    """Entry point ``rll_bt.nodes: skills``: add the skill node types and the
    ``skills`` service factory; publishes the localisation presets the service
    builds from the agent's ``services["localisation"]`` (``choices["localisation"]``)."""
    register_service("skills", skills_service, replace=True)
    for cls in NODE_TYPES:
        registry.register(cls, replace=True)
