"""The agent link: the robots' messages in, the team server's out.

The task protocol is the league's AgentTask (:mod:`rll_bt.agenttask`):
tasks and cancels go out as ``AgentTask``; results come back as the task
echoed with ``successful`` / ``canceled`` / ``error_code``, and every
robot says ``BeaconSignal`` (liveness; for a league robot also its pose and
its current and finished tasks).  A robot that opens with ``RobotHello``
speaks rll-bt: it also gets ``TaskDetail`` before each task, ``GamePhase``,
``MachineMap`` and ``Heartbeat``, and sends ``RobotStatus``, ``TaskOutcome``
before each result, ``MachineObservation`` and ``ZoneExplored``.  A robot
that never says hello (or a server run with ``extras=False``, ``rll-bt
teamserver --robots agenttask``) gets nothing but the league's messages.

Task ids on the wire name one *assignment* of a planned task: ``task id *
64 + attempt`` (:func:`wire_id`).  A task that goes back to the pool and
to a robot again is a new assignment with a new id, so a robot never
takes it for the one it already ran (and answers with that old result),
while the same assignment sent again keeps its id and runs at most once.
A result for an assignment that is over (an older attempt) is ignored.
"""
from __future__ import annotations

import logging
import math

from rll_bt import msgs
from rll_bt.agenttask import from_league, holding_after, render_cancel, render_task
from rll_bt.rules import Profile, machine_team, machine_type, mirror_machine_name

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from .docking import Docking
from .leases import Leases

log = logging.getLogger("teamserver.links.agents")

LIGHT_BITS = (("GREEN", 1), ("YELLOW", 2), ("RED", 4))
TEAM_VALUE = {"CYAN": 0, "MAGENTA": 1}
ATTEMPTS = 64                 # wire ids: task id * ATTEMPTS + attempt % ATTEMPTS


def wire_id(t: M.Task) -> int:
    """The id of ``t``'s current assignment on the wire."""
    return int(t.id) * ATTEMPTS + int(t.attempts) % ATTEMPTS


def from_wire(wire: int) -> tuple[int, int]:
    """(task id, attempt modulo ATTEMPTS) of a wire id."""
    return divmod(int(wire), ATTEMPTS)
PHASE_VALUE = {"PRE_GAME": 0, "SETUP": 10, "EXPLORATION": 20, "PRODUCTION": 30, "POST_GAME": 40}
STATE_VALUE = {"INIT": 0, "WAIT_START": 1, "RUNNING": 2, "PAUSED": 3}


def lights_of_pattern(pattern: int) -> tuple[str, ...]:
    """Light code bit set (green 1, yellow 2, red 4) -> sorted lights that are on."""
    return tuple(sorted(name for name, bit in LIGHT_BITS if pattern & bit))


class AgentLink:
    """Turns the robots' messages into knowledge-base updates and back.
    ``extras``: rll-bt's additions go to robots that speak rll-bt (False:
    nothing but the league's messages to anyone)."""

    def __init__(self, kb: KnowledgeBase, clock, extras: bool = True):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.clock = clock
        self.extras = extras
        self.ms = msgs.message_set("team")
        self.peers: dict = {}            # transport peer -> robot number
        self.rllbt_peers: set = set()    # peers that said RobotHello
        self.league_peers: set = set()   # peers that spoke without it
        self._outcomes: dict[tuple[int, int], object] = {}   # (robot, task id) -> TaskOutcome
        self.hb_seq = 0
        self.leases = Leases()              # the robots' task leases (:mod:`.leases`)
        self.running: dict[int, int] = {}   # robot -> the assignment (wire id) its latest RobotStatus says it runs
        self.docking = Docking(kb, clock)   # where a robot of the league waits (it sends no RobotStatus)

    def speaks_rllbt(self, robot: M.Robot | None) -> bool:
        """Whether rll-bt's additions may go to ``robot`` (None: to every robot)."""
        if not self.extras:
            return False
        return robot is None or robot.peer not in self.league_peers

    def dropped(self, peer) -> int | None:
        """A link closed: forget its peer; the robot number it had, if any."""
        self.rllbt_peers.discard(peer)
        self.league_peers.discard(peer)
        return self.peers.pop(peer, None)

    # -- incoming ----------------------------------------------------------------------
    def robot(self, number: int, peer=None) -> M.Robot:
        r = self.kb.robots.get(number)
        if r is None:
            r = M.Robot(number, name=f"R{number}", last_heartbeat=self.clock.now())
        if peer is not None:
            r.peer = peer
            self.peers[peer] = number
        return r

    def seen(self, r: M.Robot) -> bool:
        """Note a sign of life; True if the robot was LOST and is back."""
        r.last_heartbeat = self.clock.now()
        back = r.status != M.ACTIVE
        r.status = M.ACTIVE
        return back

    def on_hello(self, m, peer) -> M.Robot:
        self.rllbt_peers.add(peer)
        self.league_peers.discard(peer)
        r = self.robot(int(m.robot_id), peer)
        r.name = m.peer_name or r.name
        self.leases.reset(r.number)        # a new connection, perhaps a new process with a new clock
        self.seen(r)
        if m.HasField("restarted") and m.restarted:
            r.holding = None            # a rebooted robot has lost what it knew
            self.running.pop(r.number, None)     # ... and runs nothing
        self.kb.save_robot(r)
        return r

    def on_beacon(self, m, peer) -> tuple[M.Robot, bool]:
        """A robot's BeaconSignal: a sign of life (``back``: it was lost, or is
        new on this link).  A robot that never said hello is a league robot:
        the beacon is all it says about itself (name, pose, the station it waits
        at docked: :mod:`.docking`)."""
        league = peer not in self.rllbt_peers
        new = league and peer not in self.league_peers
        if league:
            self.league_peers.add(peer)
        r = self.robot(int(m.number), peer)
        back = self.seen(r) or new
        if league:
            r.name = m.peer_name or r.name
            pose = (m.pose.x, m.pose.y, m.pose.ori) if m.HasField("pose") else None
            if pose is not None:
                r.pose = pose
            r.state = "BUSY" if m.HasField("task") else "IDLE"
            wire = int(m.task.task_id) if m.HasField("task") else None
            r.waiting_at = self.docking.waiting_at(r.number, pose, wire, None if wire is None else self.task_of(wire))
            self.kb.save_robot(r)
        elif back:
            self.kb.save_robot(r)
        else:
            self.kb.robots[r.number] = r        # liveness only: no write per beacon
        return r, back

    def task_of(self, wire: int) -> M.Task | None:
        """The planned task whose current assignment ``wire`` names (None: no such
        task, or an assignment that is over)."""
        tid, attempt = from_wire(wire)
        t = self.kb.tasks.get(tid)
        return t if t is not None and int(t.attempts) % ATTEMPTS == attempt else None

    def on_outcome(self, m) -> None:
        """rll-bt's TaskOutcome: kept for the result that follows it."""
        self._outcomes[(int(m.robot_id), int(m.task_id))] = m
        while len(self._outcomes) > 256:
            self._outcomes.pop(next(iter(self._outcomes)))

    def drop_outcome(self, at) -> None:
        """Forget the TaskOutcome kept for the result ``at`` (a repeat, not acted on)."""
        self._outcomes.pop((int(at.robot_id), int(at.task_id)), None)

    def result_of(self, at) -> tuple[str, str, bool | None, str]:
        """(status, error, holding, text) of a robot's echoed AgentTask: status
        SUCCEEDED / FAILED / CANCELLED, error rll-bt's ErrorCode name (from the
        TaskOutcome before it, else the league's code in rll-bt's words)."""
        status = "CANCELLED" if at.canceled else "SUCCEEDED" if at.successful else "FAILED"
        out = self._outcomes.pop((int(at.robot_id), int(at.task_id)), None)
        code = int(at.error_code) if at.HasField("error_code") else None
        if out is not None:
            return status, self.ms.enum("ErrorCode").Name(out.error), bool(out.holding), out.text
        error = "CANCELLED" if status == "CANCELLED" else "NONE" if status == "SUCCEEDED" else from_league(code)
        return status, error, holding_after(code), ""

    def on_status(self, m, peer) -> tuple[M.Robot, bool]:
        r = self.robot(int(m.robot_id), peer)
        self.leases.status(r.number, m.stamp if m.HasField("stamp") else None,
                           m.lease_lag if m.HasField("lease_lag") else None, self.clock.now())
        back = self.seen(r)
        if m.HasField("pose"):
            r.pose = (m.pose.x, m.pose.y, m.pose.theta)
        r.gripper = m.HasField("holding")
        r.waiting_at = m.waiting_at if m.HasField("waiting_at") else None
        r.state = self.ms.enum("RobotStatus.State").Name(m.state)
        if m.HasField("current_task_id"):
            self.running[r.number] = int(m.current_task_id)
        else:
            self.running.pop(r.number, None)
        self.kb.save_robot(r)
        return r, back

    def on_observation(self, m) -> list[M.Observation]:
        """Observations from one MachineObservation (none without a machine name)."""
        name = m.name.value if m.HasField("name") else None
        if name is None and m.HasField("tag_id"):
            hit = self.profile.machine_for_tag(int(m.tag_id.value))
            name = hit[0] if hit else None
        if name is None or name not in self.profile.tags:
            return []
        robot = f"R{m.robot_id}"
        now = self.clock.now()
        out = []
        if m.HasField("pose"):
            p = m.pose.pose
            out.append(M.Observation(name, M.POSE, (p.x, p.y, p.theta), m.pose.confidence,
                                     robot, now))
            if not m.HasField("zone"):
                z = self.profile.zone_at(p.x, p.y)
                if z is not None:
                    out.append(M.Observation(name, M.ZONE, z, m.pose.confidence, robot, now))
        if m.HasField("zone") and int(m.zone.value) in self.profile.zones.all_zones:
            out.append(M.Observation(name, M.ZONE, int(m.zone.value), m.zone.confidence,
                                     robot, now))
        if m.HasField("orientation"):
            deg = self.profile.discretise_rotation(float(m.orientation.value))
            out.append(M.Observation(name, M.ORIENTATION, deg, m.orientation.confidence,
                                     robot, now))
        if m.HasField("lights") and 0 < m.lights.pattern < 8:
            source = M.view_source(robot, m.lights.view) if m.lights.HasField("view") else robot
            out.append(M.Observation(name, M.LIGHT, lights_of_pattern(m.lights.pattern),
                                     m.lights.confidence, source, now))
        if m.HasField("type"):
            out.append(M.Observation(name, M.TYPE, m.type.value, m.type.confidence, robot, now))
        for o in out:
            self.kb.add_observation(o)
        return out

    # -- outgoing --------------------------------------------------------------------------
    def task_msgs(self, t: M.Task, color: str | None, robot: M.Robot | None = None) -> list:
        """The messages that give task ``t`` to its robot: the AgentTask, after
        rll-bt's TaskDetail for a robot that speaks rll-bt.  A robot that knows
        only the league's tasks is sent a discard onto a slide instead of one
        where it stands."""
        params, extras = dict(t.params), self.speaks_rllbt(robot)
        if t.kind == M.DISCARD and not params.get("machine") and not extras:
            params.update(machine=self._slide_for(robot, color), side=M.SLIDE)
        zone = None
        if robot is not None and robot.pose is not None:
            zone = self.profile.zone_at(robot.pose[0], robot.pose[1])
        at, detail = render_task(t.kind, params, task_id=wire_id(t), robot_id=int(t.robot or 0), color=color,
                                 profile=self.profile, robot_zone=zone, issued_at=self.clock.now(),
                                 **self._workpiece(t))
        before = self.kb.tasks.get(t.after) if t.after is not None else None
        if before is not None and extras:
            detail.after = wire_id(before)          # to run once that one succeeded
        return [detail, at] if extras else [at]

    def _workpiece(self, t: M.Task) -> dict:
        """The order and the workpiece colours of ``t``'s product, for the AgentTask."""
        p = self.kb.products.get(t.product or "")
        if p is None:
            return {}
        out: dict = {"order_id": p.order_id or None}
        wp = self.kb.workpieces.get(p.workpiece or "")
        if wp is not None and wp.base:
            out["workpiece"] = (wp.base, tuple(wp.rings), wp.cap)
        return out

    def _slide_for(self, robot: M.Robot | None, color: str | None) -> str:
        """The own ring station nearest ``robot`` (whose place is known)."""
        prefix = "M-" if color == "MAGENTA" else "C-"
        names = [f"{prefix}RS1", f"{prefix}RS2"]
        if robot is None or robot.pose is None:
            return names[0]

        def dist(name):
            est = self.kb.estimate(name, M.POSE)
            if est is None:
                return math.inf
            return math.hypot(est.value[0] - robot.pose[0], est.value[1] - robot.pose[1])
        return min(names, key=dist)

    def cancel_msg(self, t: M.Task, reason: str, color: str | None = None, robot: int | None = None):
        """The AgentTask that stops ``t`` (its current assignment) on robot ``robot``
        (default: the task's; ``reason`` only for logs)."""
        return render_cancel(wire_id(t), int(robot if robot is not None else t.robot or 0), color)

    def cancel_wire(self, wire: int, robot: int, color: str | None = None):
        """The AgentTask that stops the assignment ``wire`` on robot ``robot``."""
        return render_cancel(wire, robot, color)

    def heartbeat_msg(self, number: int, timeout: float | None = None):
        """A heartbeat to robot ``number``; with ``timeout`` (the heartbeat timeout) its task
        lease (:mod:`.leases`): the latest stamp of its statuses heard, and the seconds after
        it the robot may work unheard (``timeout`` and the lag it reported), kept as granted."""
        self.hb_seq += 1
        hb = self.ms.Heartbeat(robot_id=number, seq=self.hb_seq, stamp=self.clock.now())
        granted = self.leases.grant(number, timeout) if timeout is not None else None
        if granted is not None:
            hb.heard, hb.lease = granted
        return hb

    def game_phase_msg(self, phase: str, state: str, game_time: float, color: str | None,
                       exploring: bool):
        m = self.ms.GamePhase(state=STATE_VALUE.get(state, 0), phase=PHASE_VALUE.get(phase, 0),
                              game_time=game_time, exploring=exploring,
                              profile=self.profile.name, stamp=self.clock.now())
        if color:
            m.team_color = TEAM_VALUE[color]
        return m

    def _twin_pose(self, name: str, zone: int) -> tuple[float, float, float] | None:
        """Where machine ``name`` (in ``zone``, its pose never seen) stands by its twin's
        seen pose: the field mirrors every machine's twin, within its zone and off its
        centre alike (a machine by a wall stands off its zone's centre); None when the
        twin's pose is unknown, mirrors into another zone, or the pair does not stand
        as mirror images (a 2017+ RS or CS by a wall)."""
        if not self.profile.twin_mirrors(name, zone):
            return None
        seen = self.kb.estimate(mirror_machine_name(name), M.POSE)
        if seen is None:
            return None
        x, y, theta = seen.value
        mx, my = self.profile.mirror_point(x, y)
        if self.profile.zone_at(mx, my) != zone:
            return None
        return mx, my, math.atan2(math.sin(math.pi - theta), math.cos(math.pi - theta))

    def machine_map_msg(self, consistent) -> object:
        """MachineMap of every machine whose place is known (consistent set first)."""
        mm = self.ms.MachineMap(profile=self.profile.name, stamp=self.clock.now())
        for name in sorted(self.profile.tags):
            g = consistent.machines.get(name) if consistent else None
            zone = g.zone if g is not None and g.zone is not None else None
            conf = g.zone_confidence if zone is not None else 0.0
            pose = self.kb.estimate(name, M.POSE)
            if zone is None:
                est = self.kb.estimate(name, M.ZONE)
                if est is not None:
                    zone, conf = int(est.value), est.confidence
            if zone is None and pose is None:
                continue
            km = mm.machines.add(name=name, type=machine_type(name),
                                 team_color=TEAM_VALUE[machine_team(name)])
            if pose is not None:
                km.pose.x, km.pose.y, km.pose.theta = pose.value
            rot = g.orientation if g is not None and g.orientation is not None else None
            twin = self._twin_pose(name, zone) if pose is None and zone is not None else None
            if twin is not None:
                km.pose.x, km.pose.y, km.pose.theta = twin
            elif pose is None and zone is not None:
                km.pose.x, km.pose.y = self.profile.zone_centre(zone)
                km.pose.theta = math.radians(rot or 0)
            if zone is not None:
                km.zone = zone
            if rot is not None:
                km.rotation = int(rot)
            km.input_tag, km.output_tag = self.profile.tag_ids(name)
            km.confidence = conf
        return mm
