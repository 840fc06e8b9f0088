"""The agent link: the team protocol (package ``rllbt``) between server and robots.

Incoming: RobotHello (register or re-register; answered with GamePhase,
MachineMap and the robot's current task), Heartbeat and RobotStatus
(liveness, pose, gripper), TaskResult (to the dispatcher),
MachineObservation (per-property values with confidence, into the
knowledge base), ZoneExplored (a zone visited).  Outgoing: Task,
CancelTask, MachineMap, GamePhase, Heartbeat, built here.
"""
from __future__ import annotations

import logging
import math

from rll_bt import msgs
from rll_bt.rules import CYAN, Profile, machine_team, machine_type

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase

log = logging.getLogger("teamserver.links.agents")

LIGHT_BITS = (("GREEN", 1), ("YELLOW", 2), ("RED", 4))
TEAM_VALUE = {"CYAN": 0, "MAGENTA": 1}
PHASE_VALUE = {"PRE_GAME": 0, "SETUP": 10, "EXPLORATION": 20, "PRODUCTION": 30, "POST_GAME": 40}
STATE_VALUE = {"INIT": 0, "WAIT_START": 1, "RUNNING": 2, "PAUSED": 3}


def lights_of_pattern(pattern: int) -> tuple[str, ...]:
    """Light code bit set (green 1, yellow 2, red 4) -> sorted lights that are on."""
    return tuple(sorted(name for name, bit in LIGHT_BITS if pattern & bit))


class AgentLink:
    """Turns team-protocol messages into knowledge-base updates and back."""

    def __init__(self, kb: KnowledgeBase, clock):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.clock = clock
        self.ms = msgs.message_set("team")
        self.peers: dict = {}            # transport peer -> robot number
        self.hb_seq = 0

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
        r = self.robot(int(m.robot_id), peer)
        r.name = m.peer_name or r.name
        self.seen(r)
        if m.HasField("restarted") and m.restarted:
            r.holding = None            # a rebooted robot has lost what it knew
        self.kb.save_robot(r)
        return r

    def on_heartbeat(self, m, peer) -> tuple[M.Robot, bool]:
        r = self.robot(int(m.robot_id), peer)
        back = self.seen(r)
        if back:
            self.kb.save_robot(r)
        else:
            self.kb.robots[r.number] = r        # liveness only: no write per heartbeat
        return r, back

    def on_status(self, m, peer) -> tuple[M.Robot, bool]:
        r = self.robot(int(m.robot_id), peer)
        back = self.seen(r)
        if m.HasField("pose"):
            r.pose = (m.pose.x, m.pose.y, m.pose.theta)
        r.gripper = m.HasField("holding")
        r.waiting_at = m.waiting_at if m.HasField("waiting_at") else None
        r.state = self.ms.enum("RobotStatus.State").Name(m.state)
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
            out.append(M.Observation(name, M.LIGHT, lights_of_pattern(m.lights.pattern),
                                     m.lights.confidence, robot, now))
        if m.HasField("type"):
            out.append(M.Observation(name, M.TYPE, m.type.value, m.type.confidence, robot, now))
        for o in out:
            self.kb.add_observation(o)
        return out

    # -- outgoing --------------------------------------------------------------------------
    def task_msg(self, t: M.Task, color: str | None):
        ms = self.ms
        msg = ms.Task(team_color=TEAM_VALUE.get(color or CYAN, 0), task_id=t.id, robot_id=t.robot,
                      issued_at=self.clock.now())
        p = t.params
        side = ms.enum("MachineSide")
        if t.kind == M.EXPLORE_ZONE:
            msg.explore_zone.zone = int(p["zone"])
            for x, y, theta in p.get("viewpoints", ()):
                msg.explore_zone.viewpoints.add(x=float(x), y=float(y), theta=float(theta))
        elif t.kind == M.GET_WORKPIECE:
            msg.get_workpiece.machine = p["machine"]
            msg.get_workpiece.side = side.Value(p.get("side", M.OUTPUT))
        elif t.kind == M.PUT_WORKPIECE:
            msg.put_workpiece.machine = p["machine"]
            msg.put_workpiece.side = side.Value(p.get("side", M.INPUT))
        elif t.kind == M.RETRIEVE_CAP:
            msg.retrieve_cap.machine = p["machine"]
            msg.retrieve_cap.shelf_slot = int(p.get("shelf_slot", 0))
        elif t.kind == M.MOUNT_RING:
            msg.mount_ring.machine = p["machine"]
            msg.mount_ring.ring_color = ms.enum("RingColor").Value(p["ring_color"])
        elif t.kind == M.MOUNT_CAP:
            msg.mount_cap.machine = p["machine"]
            if p.get("cap_color"):
                msg.mount_cap.cap_color = ms.enum("CapColor").Value(p["cap_color"])
        elif t.kind == M.DELIVER:
            msg.deliver.machine = p["machine"]
            if "gate" in p:
                msg.deliver.gate = int(p["gate"])
            else:
                msg.deliver.order_id = int(p["order_id"])
        elif t.kind == M.DISCARD:
            msg.discard.SetInParent()
            if p.get("machine"):
                msg.discard.machine = p["machine"]
                msg.discard.side = ms.enum("MachineSide").Value(p.get("side", M.INPUT))
        elif t.kind == M.GO_TO:
            msg.go_to.target.x, msg.go_to.target.y = float(p["x"]), float(p["y"])
            msg.go_to.target.theta = float(p.get("theta", 0.0))
            if p.get("zone"):
                msg.go_to.zone = int(p["zone"])
        else:
            raise ValueError(f"no team-protocol task for {t.kind!r}")
        return msg

    def cancel_msg(self, t: M.Task, reason: str, robot: int | None = None):
        number = t.robot if robot is None else robot
        return self.ms.CancelTask(task_id=t.id, robot_id=int(number or 0), reason=reason)

    def heartbeat_msg(self, number: int):
        self.hb_seq += 1
        return self.ms.Heartbeat(robot_id=number, seq=self.hb_seq, stamp=self.clock.now())

    def game_phase_msg(self, phase: str, state: str, game_time: float, color: str | None,
                       exploring: bool):
        m = self.ms.GamePhase(state=STATE_VALUE.get(state, 0), phase=PHASE_VALUE.get(phase, 0),
                              game_time=game_time, exploring=exploring,
                              profile=self.profile.name, stamp=self.clock.now())
        if color:
            m.team_color = TEAM_VALUE[color]
        return m

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
            if pose is None and zone is not None:
                km.pose.x, km.pose.y = self.profile.zone_centre(zone)
                km.pose.theta = math.radians(rot or 0)
            if zone is not None:
                km.zone = zone
            if rot is not None:
                km.rotation = int(rot)
            km.input_tag, km.output_tag = self.profile.tag_ids(name)
            km.confidence = conf
        return mm
