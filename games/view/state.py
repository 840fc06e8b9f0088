"""What the live page shows, kept up to date from the watch's messages.

:class:`ViewState` takes every message of a game's channels as
``feed(topic, seconds, value)`` (a :attr:`rll_bt.watch.sink.Watch.listeners`
callback; a recording or a Foxglove connection feed it the same way, see
:mod:`.sources`) and keeps, as plain JSON data:

- ``field``: the rules profile's field and zones; ``stations``: every
  station's pose, team, zone and state (``/game/stations`` and the state
  changes of ``/game/sample``, or the refbox's ``MachineInfo``);
- ``robots``: per robot its true pose, its estimated pose, the task it runs
  (``/game/task``) and its task tree (``/robotN/tree/structure``) with the
  nodes running and visited at the last tick (``/robotN/tree``);
- ``paths``: each robot's path (true pose, else estimate), ``score``: the
  team's points over time, ``events``: faults and notes (append-only);
- ``game``: phase, state, game time and points of the refbox's
  ``GameState`` (our colour: ``team`` of the metadata, a colour or the team
  name the GameState names); ``orders``: the refbox's ``OrderInfo`` with
  their delivery windows; ``result``: the end of the game.

A page gets the whole state once and then only what changed
(:meth:`ViewState.changes`): keys set since its cursor and the tails of the
append-only lists.  The state is safe to feed from one thread and read from others.
"""
from __future__ import annotations

import math
import re
import threading
from typing import Any

APPEND = ("paths", "score", "events")
_ROBOT = re.compile(r"^/robot(\d+)/(.+)$")
PATH_STEP = 0.05          # m a robot moves before its path gets a point
PATH_PERIOD = 1.0         # s after which it gets one anyway


def field_of(profile_name: str) -> dict:
    """The field and its zones of a rules profile, as the page draws them."""
    from rll_bt import rules
    prof = rules.profile(profile_name)
    f = prof.field
    zones = []
    for z in prof.zones.all_zones:
        b = prof.zones.bounds(z)
        zones.append({"name": prof.zones.name(z), "team": prof.zones.team(z), "x_min": b.x_min, "x_max": b.x_max,
                      "y_min": b.y_min, "y_max": b.y_max})
    return {"profile": profile_name, "x_min": f.x_min, "x_max": f.x_max, "y_min": f.y_min, "y_max": f.y_max,
            "zones": zones, "mps": {"width": prof.mps.width, "depth": prof.mps.depth}}


def pose_of(value) -> list[float] | None:
    """``[x, y, theta]`` of a Pose2D, a foxglove PoseInFrame or a pose dict."""
    if value is None:
        return None
    if hasattr(value, "theta") and hasattr(value, "x"):
        return [round(float(value.x), 3), round(float(value.y), 3), round(float(value.theta), 3)]
    pose = getattr(value, "pose", None)
    if pose is not None and hasattr(pose, "position"):
        p, q = pose.position, pose.orientation
        theta = 2.0 * math.atan2(q.z, q.w) if (q.z or q.w) else 0.0
        return [round(p.x, 3), round(p.y, 3), round(theta, 3)]
    if isinstance(value, dict):
        p = value.get("pose", value)
        if "position" in p:
            q = p.get("orientation", {})
            return [round(p["position"].get("x", 0.0), 3), round(p["position"].get("y", 0.0), 3),
                    round(2.0 * math.atan2(q.get("z", 0.0), q.get("w", 1.0)), 3)]
    return None


def proto_dict(msg) -> dict:
    """A protobuf message (generated or decoded from a schema) as a dict, enums by name."""
    if isinstance(msg, dict):
        return msg
    from google.protobuf.json_format import MessageToDict
    return MessageToDict(msg, preserving_proto_field_name=True)


class ViewState:
    """See the module doc.  ``profile``: the rules profile the field is drawn
    for (a recording's or game's metadata may name another: :meth:`set_meta`)."""

    def __init__(self, profile: str = "rcll2016", meta: dict | None = None, team: str = "CYAN"):
        self._lock = threading.Condition()
        self.epoch = 0
        self._reset(profile, meta or {}, team)

    def _reset(self, profile: str, meta: dict, team: str) -> None:
        self.version = 0
        self._changed: dict[str, int] = {}
        self.data: dict[str, Any] = {
            "meta": {"profile": profile, "team": team, **meta}, "field": field_of(profile), "t": 0.0,
            "stations": {}, "robots": {}, "game": {}, "orders": [], "result": None,
            "paths": {}, "score": [], "events": []}
        if team in ("CYAN", "MAGENTA"):
            self.data["meta"]["color"] = team
        self._path_src: dict[str, str] = {}
        self._path_last: dict[str, list] = {}
        self._team = team
        self.messages = 0
        for key in ("meta", "field", "t", "stations", "robots", "game", "orders", "result"):
            self._touch(key)

    # -- change tracking ----------------------------------------------------------------------------
    def _touch(self, key: str) -> None:
        self.version += 1
        self._changed[key] = self.version

    def reset(self, profile: str | None = None, meta: dict | None = None) -> None:
        """Start over (a replay seeking back): every page gets the whole state again."""
        with self._lock:
            d = self.data
            self.epoch += 1
            self._reset(profile or d["meta"]["profile"], meta if meta is not None else
                        {k: v for k, v in d["meta"].items() if k not in ("profile", "team")}, self._team)
            self._lock.notify_all()

    def set_meta(self, **meta) -> None:
        with self._lock:
            m = self.data["meta"]
            if meta.get("profile") and meta["profile"] != m.get("profile"):
                try:
                    self.data["field"] = field_of(meta["profile"])
                    self._touch("field")
                except KeyError:
                    meta.pop("profile")
            if meta.get("team"):
                self._team = meta["team"]
            m.update({k: v for k, v in meta.items() if v is not None})
            self._touch("meta")
            self._lock.notify_all()

    def put(self, key: str, value) -> None:
        """Set a key of its own (a replay's ``playback``)."""
        with self._lock:
            self.data[key] = value
            self._touch(key)
            self._lock.notify_all()

    def snapshot(self) -> dict:
        """The whole state and the cursor to ask for changes with."""
        with self._lock:
            import copy
            return {"reset": True, "cursor": self._cursor(), "set": copy.deepcopy(
                {k: v for k, v in self.data.items() if k not in APPEND}),
                "append": copy.deepcopy({k: self.data[k] for k in APPEND})}

    def _cursor(self) -> dict:
        d = self.data
        return {"epoch": self.epoch, "v": self.version,
                "n": {"score": len(d["score"]), "events": len(d["events"]),
                      **{f"paths/{r}": len(p) for r, p in d["paths"].items()}}}

    def changes(self, cursor: dict | None) -> dict | None:
        """What changed since ``cursor`` (None: nothing; the whole state after a reset)."""
        if cursor is None or cursor.get("epoch") != self.epoch:
            return self.snapshot()
        with self._lock:
            if self.version == cursor["v"]:
                return None
            import copy
            d = self.data
            out: dict = {"cursor": self._cursor(), "set": {}, "append": {}}
            for key, v in self._changed.items():
                if v > cursor["v"]:
                    out["set"][key] = copy.deepcopy(_get(d, key))
            n = cursor.get("n", {})
            for key in ("score", "events"):
                if len(d[key]) > n.get(key, 0):
                    out["append"][key] = d[key][n.get(key, 0):]
            paths = {r: p[n.get(f"paths/{r}", 0):] for r, p in d["paths"].items() if len(p) > n.get(f"paths/{r}", 0)}
            if paths:
                out["append"]["paths"] = paths
            return out

    def wait(self, version: int, timeout: float) -> None:
        """Until the state is newer than ``version`` (or ``timeout`` s)."""
        with self._lock:
            if self.version == version:
                self._lock.wait(timeout)

    # -- feeding ------------------------------------------------------------------------------------
    def feed(self, topic: str, t: float, value) -> None:
        """One message of a watch (``Watch.listeners`` signature)."""
        with self._lock:
            self.messages += 1
            if t > self.data["t"]:
                self.data["t"] = round(t, 3)
                self._touch("t")
            try:
                self._feed(topic, t, value)
            except (AttributeError, KeyError, TypeError, ValueError, IndexError):
                pass                   # a message of another shape: nothing to show of it
            self._lock.notify_all()

    def _feed(self, topic: str, t: float, value) -> None:
        m = _ROBOT.match(topic)
        if m:
            self._robot(m.group(1), m.group(2), t, value)
        elif topic.startswith("/game/"):
            self._game(topic[6:], t, value)
        elif topic.endswith("/GameState"):
            self._game_state(t, proto_dict(value))
        elif topic.endswith("/OrderInfo"):
            self._orders(proto_dict(value))
        elif topic.endswith("/MachineInfo"):
            self._machines(proto_dict(value))

    def _robot_entry(self, n: str) -> dict:
        robots = self.data["robots"]
        if n not in robots:
            robots[n] = {"pose": None, "true_pose": None, "task": None, "tree": None}
        return robots[n]

    def _robot(self, n: str, what: str, t: float, value) -> None:
        if what in ("pose", "true_pose"):
            pose = pose_of(value)
            if pose is None:
                return
            self._robot_entry(n)[what] = pose
            self._touch(f"robots/{n}")
            self._path(n, what, t, pose)
        elif what == "tree/structure":
            d = dict(value)
            if "task_id" not in d:
                return
            self._robot_entry(n)["tree"] = {"task_id": d.get("task_id"), "kind": d.get("kind"),
                                            "name": d.get("name"), "nodes": d.get("nodes", []), "running": [],
                                            "visited": [], "status": None, "tick": 0, "outcome": None}
            self._touch(f"robots/{n}")
        elif what == "tree":
            tree = (self.data["robots"].get(n) or {}).get("tree")
            if tree is None or tree["task_id"] != value.get("task_id"):
                return
            tree.update(running=value.get("running", []), visited=value.get("visited", []),
                        status=value.get("status"), tick=value.get("tick", 0))
            if value.get("outcome"):
                tree["outcome"] = value["outcome"]
                tree["running"] = []
            self._touch(f"robots/{n}")

    def _path(self, n: str, what: str, t: float, pose: list) -> None:
        src = self._path_src.get(n)
        if src == "pose" and what == "true_pose":     # the truth, once there is one, draws the path
            self.data["paths"][n] = []
            self._path_last.pop(n, None)
            self.epoch += 1                           # a list was cut: pages start over
        elif src is not None and src != what:
            return
        self._path_src[n] = what
        last = self._path_last.get(n)
        if last is not None and math.hypot(pose[0] - last[1], pose[1] - last[2]) < PATH_STEP \
                and t - last[0] < PATH_PERIOD:
            return
        point = [round(t, 2), pose[0], pose[1]]
        self._path_last[n] = point
        self.data["paths"].setdefault(n, []).append(point)
        self.version += 1

    def _game(self, kind: str, t: float, d: dict) -> None:
        if kind == "sample":
            changes = d.get("stations") or {}
            for name, (_t, state) in changes.items():
                st = self.data["stations"].setdefault(name, {"name": name})
                st["state"] = state
            if changes:
                self._touch("stations")
        elif kind == "stations":
            self.data["stations"] = {s["name"]: dict(s) for s in d["stations"]}
            self._touch("stations")
        elif kind == "task":
            robot = self._robot_entry(str(int(d["robot"])))
            robot["task"] = None if d.get("end") is not None else {"kind": d.get("kind"), "id": d.get("id"),
                                                                    "start": d.get("start")}
            self._touch(f"robots/{d['robot']}")
        elif kind == "event":
            self.data["events"].append(dict(d))
            self.version += 1
        elif kind == "result":
            self.data["result"] = {k: d.get(k) for k in ("finished", "sim_time", "points", "collisions", "messages")}
            self._touch("result")
            if d.get("orders"):
                self.data["orders"] = [_order(o) for o in d["orders"]]
                self._touch("orders")

    def _score(self, t: float, points: int, phase: str | None, game_time: float | None) -> None:
        score = self.data["score"]
        if score and score[-1][1] == points and score[-1][2] == phase and t - score[-1][0] < 5.0:
            return
        score.append([round(t, 2), int(points), phase, None if game_time is None else round(game_time, 1)])
        self.version += 1

    def _game_state(self, t: float, d: dict) -> None:
        gt = d.get("game_time", {})
        game_time = float(gt.get("sec", 0)) + float(gt.get("nsec", 0)) / 1e9 if isinstance(gt, dict) else float(gt)
        points = {"CYAN": int(d.get("points_cyan", 0)), "MAGENTA": int(d.get("points_magenta", 0))}
        if self._team not in points:           # a team name: its colour is in the GameState
            if self._team == d.get("team_cyan"):
                self._team = "CYAN"
            elif self._team == d.get("team_magenta"):
                self._team = "MAGENTA"
            else:
                return
            self.data["meta"]["color"] = self._team
            self._touch("meta")
        self.data["game"] = {"phase": d.get("phase", "PRE_GAME"), "state": d.get("state", "INIT"),
                             "game_time": round(game_time, 1), "points": points, "color": self._team}
        self._touch("game")
        self._score(t, points[self._team], d.get("phase"), game_time)

    def _orders(self, d: dict) -> None:
        orders = [_order(o) for o in d.get("orders", [])]
        if orders != self.data["orders"]:
            self.data["orders"] = orders
            self._touch("orders")

    def _machines(self, d: dict) -> None:
        changed = False
        for mm in d.get("machines", []):
            name = mm.get("name")
            if not name:
                continue
            st = self.data["stations"].setdefault(name, {"name": name})
            new = {"state": mm.get("state", st.get("state"))}
            if "team_color" in mm:
                new["team"] = mm["team_color"]
            if "pose" in mm:
                p = mm["pose"]
                new["pose"] = [p.get("x", 0.0), p.get("y", 0.0), p.get("ori", 0.0)]
            for k, v in new.items():
                if v is not None and st.get(k) != v:
                    st[k] = v
                    changed = True
        if changed:
            self._touch("stations")


def _order(o: dict) -> dict:
    """An order as the page shows it: ``OrderInfo``'s fields, or a game result's (the refbox's own)."""
    complexity = o.get("complexity", "C0")
    delivered = o.get("delivered")
    if not isinstance(delivered, dict):
        delivered = {"CYAN": o.get("quantity_delivered_cyan", 0), "MAGENTA": o.get("quantity_delivered_magenta", 0)}
    return {"id": o.get("id"), "complexity": f"C{complexity}" if isinstance(complexity, int) else str(complexity),
            "base": o.get("base_color", o.get("base")), "rings": list(o.get("ring_colors", o.get("rings", []))),
            "cap": o.get("cap_color", o.get("cap")),
            "requested": int(o.get("quantity_requested", o.get("quantity", 1)) or 0),
            "delivered": {k: int(delivered.get(k, 0) or 0) for k in ("CYAN", "MAGENTA")},
            "begin": o.get("delivery_period_begin", o.get("begin")), "end": o.get("delivery_period_end", o.get("end")),
            "competitive": bool(o.get("competitive", False))}


def _get(d: dict, key: str):
    for part in key.split("/"):
        d = d.get(part) if isinstance(d, dict) else None
    return d


__all__ = ["ViewState", "field_of", "pose_of", "proto_dict"]
