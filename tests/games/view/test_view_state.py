"""The live page's state: what it keeps of a game's messages, and the
changes a page gets after the whole state once."""
from __future__ import annotations

import pytest

from games.view.state import ViewState, field_of, pose_of
from rll_bt import msgs
from rll_bt.backend import Pose2D

RM = msgs.message_set("rcll2016")


def game_state(phase=20, points_cyan=0, t=10, cyan="Testers"):
    gs = RM.get("GameState")(state=2, phase=phase, points_cyan=points_cyan, team_cyan=cyan)
    gs.game_time.sec, gs.game_time.nsec = t, 500_000_000
    return gs


def structure(task_id=4):
    return {"task_id": task_id, "kind": "go_to", "name": "go to", "nodes": [
        {"id": 0, "parent": None, "depth": 0, "name": "root", "type": "sequence"},
        {"id": 1, "parent": 0, "depth": 1, "name": "drive", "type": "drive_to"},
        {"id": 2, "parent": 0, "depth": 1, "name": "say", "type": "log"}]}


def test_the_field_of_each_profile():
    f16, f25 = field_of("rcll2016"), field_of("rcll2025")
    assert (f16["x_min"], f16["x_max"], f16["y_max"], len(f16["zones"])) == (-6.0, 6.0, 6.0, 24)
    assert f25["x_max"] == 7.0 and f25["y_max"] == 8.0 and len(f25["zones"]) > 24
    assert {z["team"] for z in f16["zones"]} == {"CYAN", "MAGENTA"} and f16["mps"]["width"] > 0


def test_poses_of_every_shape():
    assert pose_of(Pose2D(1.0, 2.0, 0.5)) == [1.0, 2.0, 0.5]
    from foxglove.messages import Pose, PoseInFrame, Vector3
    from mcap.records import Schema
    from mcap_protobuf.decoder import DecoderFactory

    from rll_bt.watch.sink import quaternion
    p = PoseInFrame(frame_id="field", pose=Pose(position=Vector3(x=3.0, y=-1.0, z=0.0), orientation=quaternion(-1.2)))
    schema = PoseInFrame.get_schema()           # as a recording or a live Foxglove server carries it
    decode = DecoderFactory().decoder_for("protobuf", Schema(id=1, name=schema.name, encoding="protobuf",
                                                             data=bytes(schema.data)))
    assert pose_of(decode(p.encode())) == [3.0, -1.0, -1.2]
    assert pose_of({"pose": {"position": {"x": 1, "y": 1}, "orientation": {"z": 0.0, "w": 1.0}}}) == [1, 1, 0.0]
    assert pose_of(None) is None and pose_of("junk") is None


def test_robots_paths_trees_score_orders_and_stations():
    s = ViewState("rcll2016", meta={"kind": "sim"}, team="CYAN")
    for i in range(20):
        s.feed("/robot1/true_pose", i * 0.1, Pose2D(1.0 + 0.1 * i, 2.0, 0.0))
        s.feed("/robot1/pose", i * 0.1, Pose2D(1.0 + 0.1 * i, 2.05, 0.0))
    s.feed("/robot1/tree/structure", 2.0, structure())
    s.feed("/robot1/tree", 2.1, {"task_id": 4, "tick": 1, "status": "RUNNING",
                                 "visited": [[0, "RUNNING"], [1, "RUNNING"]], "running": [0, 1]})
    s.feed("/robot1/tree", 2.1, {"task_id": 99, "tick": 1, "status": "FAILURE", "visited": [], "running": []})  # stale
    s.feed("/refbox/public/GameState", 2.2, game_state(points_cyan=5))
    s.feed("/refbox/public/GameState", 2.3, game_state(points_cyan=5))
    s.feed("/refbox/public/GameState", 3.0, game_state(points_cyan=9))
    order = RM.get("OrderInfo")()
    o = order.orders.add(id=1, complexity=1, base_color=1, cap_color=1, quantity_requested=2, quantity_delivered_cyan=1,
                         quantity_delivered_magenta=0, delivery_period_begin=100, delivery_period_end=300,
                         delivery_gate=1)
    o.ring_colors.append(1)
    s.feed("/refbox/public/OrderInfo", 3.0, order)
    s.feed("/game/stations", 3.0, {"stations": [{"name": "C-BS", "team": "CYAN", "zone": 9, "rotation": 270,
                                                 "pose": [5.0, 1.0, 4.7], "state": "IDLE", "light": []}]})
    s.feed("/game/sample", 3.5, {"t": 3.5, "stations": {"C-BS": [3.5, "PREPARED"]}})
    s.feed("/game/task", 3.6, {"robot": 1, "index": 0, "kind": "go_to", "id": 4, "start": 2.0, "end": None})
    s.feed("/game/event", 3.7, {"t": 3.7, "what": "agent killed", "robot": 2})
    d = s.snapshot()
    st, ap = d["set"], d["append"]
    r1 = st["robots"]["1"]
    assert r1["true_pose"] == [2.9, 2.0, 0.0] and r1["pose"] == [2.9, 2.05, 0.0]
    assert r1["task"] == {"kind": "go_to", "id": 4, "start": 2.0}
    assert r1["tree"]["running"] == [0, 1] and r1["tree"]["status"] == "RUNNING" and len(r1["tree"]["nodes"]) == 3
    # the path follows the truth, a point every 5 cm
    assert [p[1] for p in ap["paths"]["1"]] == pytest.approx([1.0 + 0.1 * i for i in range(20)])
    assert st["game"] == {"phase": "EXPLORATION", "state": "RUNNING", "game_time": 10.5, "points": {"CYAN": 9,
                                                                                                    "MAGENTA": 0},
                          "color": "CYAN"}
    assert [p[1] for p in ap["score"]] == [5, 9]               # a repeat changes nothing
    assert st["orders"] == [{"id": 1, "complexity": "C1", "base": "BASE_RED", "rings": ["RING_BLUE"],
                             "cap": "CAP_BLACK", "requested": 2, "delivered": {"CYAN": 1, "MAGENTA": 0},
                             "begin": 100, "end": 300, "competitive": False}]
    assert st["stations"]["C-BS"]["state"] == "PREPARED" and st["stations"]["C-BS"]["pose"] == [5.0, 1.0, 4.7]
    assert ap["events"] == [{"t": 3.7, "what": "agent killed", "robot": 2}]
    assert st["t"] == 3.7


def test_a_page_gets_only_what_changed_after_the_whole_state():
    s = ViewState("rcll2016", team="CYAN")
    s.feed("/robot2/true_pose", 0.0, Pose2D(0, 0, 0))
    first = s.changes(None)
    assert first["reset"] and "2" in first["set"]["robots"]
    assert s.changes(first["cursor"]) is None                    # nothing new
    s.feed("/robot2/true_pose", 1.0, Pose2D(1, 0, 0))
    s.feed("/refbox/public/GameState", 1.0, game_state(points_cyan=3))
    d = s.changes(first["cursor"])
    assert not d.get("reset") and set(d["set"]) == {"robots/2", "game", "t"}
    assert d["append"] == {"paths": {"2": [[1.0, 1, 0]]}, "score": [[1.0, 3, "EXPLORATION", 10.5]]}
    assert s.changes(d["cursor"]) is None
    s.reset()
    again = s.changes(d["cursor"])
    assert again["reset"] and again["set"]["robots"] == {}       # a replay seeking back: the page starts over


def test_a_team_named_by_name_finds_its_colour_in_the_game_state():
    s = ViewState("rcll2016", team="Testers")
    s.feed("/refbox/public/GameState", 1.0, game_state(points_cyan=0, cyan="Others"))
    assert s.data["game"] == {} and s.data["score"] == []         # not our game (yet)
    gs = game_state(points_cyan=0, cyan="Others")
    gs.team_magenta, gs.points_magenta = "Testers", 7
    s.feed("/refbox/public/GameState", 2.0, gs)
    assert s.data["game"]["color"] == "MAGENTA" and s.data["score"][-1][1] == 7


def test_machine_info_places_stations_and_junk_is_ignored():
    s = ViewState("rcll2016")
    mi = RM.get("MachineInfo")()
    m = mi.machines.add(name="C-CS1", type="CS", state="IDLE", team_color=0)
    m.pose.x, m.pose.y, m.pose.ori = 1.5, 2.5, 0.5
    m.pose.timestamp.sec, m.pose.timestamp.nsec = 0, 0
    s.feed("/refbox/cyan/MachineInfo", 1.0, mi)        # what a lone agent or team server hears of its stations
    assert s.data["stations"]["C-CS1"] == {"name": "C-CS1", "state": "IDLE", "team": "CYAN", "pose": [1.5, 2.5, 0.5]}
    before = s.snapshot()["set"]
    for topic, value in [("/robot1/tree", {"no": "task id"}), ("/game/sample", {"stations": "x"}),
                         ("/robot1/pose", "not a pose"), ("/game/task", {}), ("/refbox/public/GameState", {"x": 1})]:
        s.feed(topic, 2.0, value)
    after = s.snapshot()["set"]
    assert {k: v for k, v in after.items() if k not in ("t", "game")} == \
        {k: v for k, v in before.items() if k not in ("t", "game")}


def test_the_orders_of_a_game_result_show_like_the_refboxs():
    s = ViewState("rcll2016")
    s.feed("/game/result", 50.0, {"finished": True, "sim_time": 50.0, "points": {"CYAN": 4}, "collisions": 0,
                                  "messages": 10, "orders": [
                                      {"id": 2, "complexity": 1, "base": "BASE_RED", "rings": ["RING_BLUE"],
                                       "cap": "CAP_GREY", "quantity": 1, "gate": 1, "begin": 10, "end": 90,
                                       "activate_at": 0, "competitive": True, "delivered": {"CYAN": 1, "MAGENTA": 0}}]})
    assert s.data["orders"] == [{"id": 2, "complexity": "C1", "base": "BASE_RED", "rings": ["RING_BLUE"],
                                 "cap": "CAP_GREY", "requested": 1, "delivered": {"CYAN": 1, "MAGENTA": 0},
                                 "begin": 10, "end": 90, "competitive": True}]
    assert s.data["result"] == {"finished": True, "sim_time": 50.0, "points": {"CYAN": 4}, "collisions": 0,
                                "messages": 10}
