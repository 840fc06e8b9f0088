"""A lockstep game on Foxglove channels: ``rll-bt sim --record game.mcap`` and ``--live PORT``.

Topics (times are the simulation clock, see :mod:`rll_bt.watch.sink`):

- ``/refbox/<channel>/<Type>`` (the refbox's protobuf): every message the
  refbox sends (``public``, ``cyan``, ``magenta``, ``refbox`` the control stream);
- ``/robotN/<channel>/<Type>``, ``/teamserver/<channel>/<Type>`` (protobuf):
  every message a robot or the team server sends; ``link`` is the
  team-server link (AgentTask protocol);
- ``/robotN/pose``, ``/robotN/true_pose`` (``foxglove.PoseInFrame``): the
  agent's estimate; the simulation's ground truth;
- ``/robotN/scan``, ``/robotN/camera``, ``/robotN/detections``
  (``foxglove.LaserScan``, ``foxglove.CompressedImage``, JSON): what the
  robot's skills read (:mod:`rll_bt.watch.robot`);
- ``/robotN/tree``, ``/robotN/tree/structure`` (JSON): every tick of the task trees;
- ``/field`` (``foxglove.SceneUpdate``): the field, zones and stations
  (coloured by team, labelled with their state);
- ``/game/sample`` (JSON): the recorder's sample: phase, game time, points,
  true positions, station state changes;
- ``/game/task``, ``/game/event`` (JSON): robot task intervals; faults and notes;
- ``/game/stations``, ``/game/result`` (JSON): the stations as they really
  are; the end of the game and its summary.

``rll-bt replay`` rebuilds the game's recording from the ``/game/...``
topics (:mod:`.replay`) and draws the report again.
"""
from __future__ import annotations

import re
from dataclasses import asdict

from rll_bt.comm.msglog import FrameDecoder
from rll_bt.watch.robot import RobotWatch
from rll_bt.watch.sink import Watch

TEAM_RGB = {"CYAN": (0.09, 0.72, 0.82), "MAGENTA": (0.82, 0.09, 0.6)}
SAMPLE_SCHEMA = {"title": "rllbt.GameSample", "type": "object"}
_CHANNEL_NAMES = {"teamserver": "link"}


def sender(source) -> str:
    """A bus endpoint's name as a topic prefix: ``R2`` -> ``robot2``."""
    text = str(source)
    m = re.fullmatch(r"R(\d+)", text)
    if m:
        return f"robot{m.group(1)}"
    return re.sub(r"[^A-Za-z0-9_]+", "_", text).strip("_").lower() or "unknown"


def topic_for(channel: str, source, msg) -> str:
    return f"/{sender(source)}/{_CHANNEL_NAMES.get(channel, channel)}/{msg.DESCRIPTOR.name}"


class GameWatch:
    """Everything of a :class:`~games.lockstep.LockstepGame` on a :class:`Watch`."""

    def __init__(self, game, options):
        o = options
        self.game = game
        # the profile in the name: a page following the live server (rll-bt view ws://...) draws its field
        self.watch = Watch(record=o.record, live=o.live, clock=game.clock,
                           name=f"rll-bt sim ({o.profile}, seed {o.seed})",
                           meta={"kind": "sim", "team": "CYAN", **{k: getattr(o, k) for k in (
                               "profile", "seed", "robots", "strategy", "perception", "baseline", "until", "setup",
                               "exploration", "production")}})
        self.decoder = FrameDecoder({"teamserver": game.team_reg}, game.ref_reg, key=o.key)
        self.robots: dict[int, RobotWatch] = {}
        self.camera_hz = o.record_camera
        self.undecoded = 0
        self._next_truth = -1e18
        self.truth_period = 0.1
        self._station_states: dict[str, str] = {}
        if o.live is not None:
            self._declare(o)
        game.bus.tap(self.tap)

    def _declare(self, o) -> None:
        """The channels a Foxglove layout opens, created before anyone connects (see Watch.declare)."""
        from rll_bt import msgs
        from rll_bt.watch.robot import DETECTIONS_SCHEMA, STRUCTURE_SCHEMA, TREE_SCHEMA
        w = self.watch
        for n in range(1, o.robots + 1):
            for what, kind in (("pose", "PoseInFrame"), ("true_pose", "PoseInFrame"), ("scan", "LaserScan"),
                               ("camera", "CompressedImage")):
                w.declare(f"/robot{n}/{what}", kind)
            for what, schema in (("tree", TREE_SCHEMA), ("tree/structure", STRUCTURE_SCHEMA),
                                 ("detections", DETECTIONS_SCHEMA)):
                w.declare(f"/robot{n}/{what}", "json", schema)
        w.declare("/field", "SceneUpdate")
        for kind in ("sample", "task", "event", "stations", "result"):
            w.declare(f"/game/{kind}", "json", SAMPLE_SCHEMA)
        ms = msgs.message_set(o.profile)
        for name in ("GameState", "OrderInfo", "MachineInfo", "RobotInfo"):
            w.declare(f"/refbox/public/{name}", "proto", ms.get(name))

    @property
    def port(self) -> int | None:
        return self.watch.port

    # -- parts ----------------------------------------------------------------------------
    def robot(self, number: int) -> RobotWatch:
        """A new robot watch for robot ``number`` (a restarted agent gets a new one)."""
        rw = RobotWatch(self.watch, number, force_camera_hz=self.camera_hz)
        self.robots[number] = rw
        return rw

    def tap(self, channel: str, source, frame: bytes) -> None:
        msg, _cause = self.decoder.decode(channel, frame)
        if msg is None:
            self.undecoded += 1
            return
        self.watch.proto(topic_for(channel, source, msg), msg)

    def recorded(self, kind: str, data: dict) -> None:
        """A :class:`~games.recorder.Recorder` listener."""
        self.watch.json(f"/game/{kind}", data, schema=SAMPLE_SCHEMA)
        if kind == "sample" and data.get("stations"):
            self.stations()

    def round(self) -> None:
        now = self.game.clock.now()
        if now < self._next_truth - 1e-6:
            return
        nxt = self._next_truth + self.truth_period
        self._next_truth = nxt if nxt > now else now + self.truth_period
        for n in self.game.robot_numbers:
            self.watch.pose(f"/robot{n}/true_pose", self.game.world.robot_pose("CYAN", n))

    def stations(self) -> None:
        stations = self.game.refbox.stations()
        self.watch.json("/game/stations", {"stations": [station_record(s) for s in stations.values()]},
                        schema=SAMPLE_SCHEMA)
        self.watch.scene("/field", field_scene(self.game.options.rules, stations))

    def result(self, result, summary: dict | None = None) -> None:
        self.stations()
        self.watch.json("/game/result", result_record(result), schema=SAMPLE_SCHEMA)

    def close(self) -> None:
        self.watch.close()


def result_record(result) -> dict:
    """``/game/result``: the end of a game and what the report needs of it."""
    return {"finished": bool(result.finished), "sim_time": result.sim_time, "status": asdict(result.status),
            "points": result.status.points, "collisions": result.collisions, "messages": result.messages,
            "collision_log": [list(c) for c in result.collision_log],
            "team_server_restarts": result.snapshot.get("restarts", 0), "orders": result.orders,
            "awards": [asdict(a) for a in result.awards], "deliveries": [asdict(d) for d in result.deliveries]}


def station_record(s) -> dict:
    """A station of ``/game/stations``."""
    return {"name": s.name, "team": s.team, "zone": s.zone, "rotation": s.rotation,
            "pose": [s.pose.x, s.pose.y, s.pose.theta], "state": s.state, "light": list(s.light)}


def field_scene(profile, stations: dict) -> list:
    """The field as ``foxglove.SceneEntity`` objects: the floor, the zones'
    outlines, each station as a box in its team's colour with its name and state."""
    from foxglove.messages import (
        Color,
        CubePrimitive,
        LinePrimitive,
        LinePrimitiveLineType,
        Point3,
        Pose,
        SceneEntity,
        TextPrimitive,
        Vector3,
    )

    from rll_bt.watch.sink import quaternion
    f = profile.field

    def pose(x, y, z=0.0, theta=0.0):
        return Pose(position=Vector3(x=x, y=y, z=z), orientation=quaternion(theta))

    floor = CubePrimitive(pose=pose((f.x_min + f.x_max) / 2, (f.y_min + f.y_max) / 2, -0.01),
                          size=Vector3(x=f.x_max - f.x_min, y=f.y_max - f.y_min, z=0.02),
                          color=Color(r=0.85, g=0.85, b=0.85, a=1.0))
    lines = []
    for zone in profile.zones.all_zones:
        b = profile.zones.bounds(zone)
        pts = [Point3(x=x, y=y, z=0.001) for x, y in ((b.x_min, b.y_min), (b.x_max, b.y_min), (b.x_max, b.y_max),
                                                      (b.x_min, b.y_max), (b.x_min, b.y_min))]
        lines.append(LinePrimitive(type=LinePrimitiveLineType.LineStrip, pose=pose(0, 0), thickness=0.01,
                                   scale_invariant=False, points=pts, color=Color(r=0.5, g=0.5, b=0.5, a=0.6)))
    entities = [SceneEntity(frame_id="field", id="floor", cubes=[floor], lines=lines)]
    for name, s in sorted(stations.items()):
        r, g, b = TEAM_RGB.get(s.team, (0.6, 0.6, 0.6))
        cube = CubePrimitive(pose=pose(s.pose.x, s.pose.y, 0.35, s.pose.theta),
                             size=Vector3(x=profile.mps.depth, y=profile.mps.width, z=0.7),
                             color=Color(r=r, g=g, b=b, a=0.8))
        text = TextPrimitive(pose=pose(s.pose.x, s.pose.y, 0.9), billboard=True, font_size=14.0,
                             scale_invariant=True, color=Color(r=0, g=0, b=0, a=1), text=f"{name}\n{s.state}")
        entities.append(SceneEntity(frame_id="field", id=f"station/{name}", cubes=[cube], texts=[text]))
    return entities


__all__ = ["GameWatch", "field_scene", "result_record", "sender", "station_record", "topic_for"]
