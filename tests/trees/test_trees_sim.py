"""Every task tree runs to success through the real skills in the PyBullet
world (oracle perception), driven by a real agent; a failing grab makes
the grab recovery fire."""
from __future__ import annotations

import pytest

from rll_bt.agenttask import league_name
from tests.support.tree_sim import TM, SimTaskRig, error, status


@pytest.fixture
def rig():
    r = SimTaskRig()
    yield r
    r.close()


def ok(result) -> bool:
    return status(result) == "SUCCEEDED"


def test_explore_zone_finds_the_station_and_reports_it(rig):
    zone = rig.world.station("C-CS1").zone
    res = rig.task("explore_zone", zone=zone)
    assert ok(res), res
    rig.step(0.2)
    named = [m for m in rig.server.of("MachineObservation") if m.HasField("name")]
    cs1 = [m for m in named if m.name.value == "C-CS1"]
    assert cs1 and cs1[-1].zone.value == zone
    truth = rig.world.station("C-CS1").pose
    assert abs(cs1[-1].pose.pose.x - truth.x) < 0.15 and abs(cs1[-1].pose.pose.y - truth.y) < 0.15
    assert len(named) < 40                                          # changes only, not every sighting
    done = rig.server.of("ZoneExplored")
    assert [(d.zone, list(d.machines)) for d in done] == [(zone, ["C-CS1"])]
    assert rig.world.collision_count == 0


@pytest.mark.slow
def test_a_product_from_base_to_delivery(rig):
    w = rig.world
    w.spawn_workpiece("C-BS", "output", "BASE_RED")
    assert ok(rig.task("get_workpiece", machine="C-BS", side="OUTPUT"))
    base = rig.held()
    assert base is not None and base.base == "BASE_RED"
    assert ok(rig.task("mount_ring", machine="C-RS1", ring_color="RING_BLUE"))
    assert rig.held() is None and w.workpiece_at("C-RS1", "input").id == base.id
    w.move_workpiece("C-RS1", "input", "output")                    # the station did its work
    assert ok(rig.task("get_workpiece", machine="C-RS1", side="OUTPUT"))
    assert ok(rig.task("mount_cap", machine="C-CS1", cap_color="CAP_GREY"))
    assert w.workpiece_at("C-CS1", "input").id == base.id
    w.move_workpiece("C-CS1", "input", "output")
    assert ok(rig.task("get_workpiece", machine="C-CS1", side="OUTPUT"))
    assert ok(rig.task("deliver", machine="C-DS", gate=2))
    assert w.workpiece_at("C-DS", "input").id == base.id
    assert w.collision_count == 0


@pytest.mark.slow
def test_caps_from_the_shelf(rig):
    w = rig.world
    w.spawn_workpiece("C-CS1", "shelf1", "BASE_BLACK", cap="CAP_GREY")
    assert ok(rig.task("retrieve_cap", machine="C-CS1", shelf_slot=1))
    assert w.workpiece_at("C-CS1", "input").cap == "CAP_GREY" and w.workpiece_at("C-CS1", "shelf1") is None
    w.spawn_workpiece("C-CS2", "shelf0", "BASE_BLACK", cap="CAP_BLACK")
    assert ok(rig.task("get_workpiece", machine="C-CS2", side="SHELF", shelf_slot=0))
    assert rig.held().cap == "CAP_BLACK"
    assert ok(rig.task("put_workpiece", machine="C-CS2", side="INPUT"))
    assert w.workpiece_at("C-CS2", "input").cap == "CAP_BLACK"
    assert w.collision_count == 0


@pytest.mark.slow
def test_slides_and_discards(rig):
    w = rig.world
    for base in ("BASE_BLACK", "BASE_SILVER", "BASE_RED"):
        w.spawn_workpiece("C-BS", "output", base)
        assert ok(rig.task("get_workpiece", machine="C-BS", side="OUTPUT"))
        if base == "BASE_BLACK":
            assert ok(rig.task("put_workpiece", machine="C-RS2", side="SLIDE"))
            assert [wp.base for wp in w.workpieces_at("C-RS2", "slide")] == ["BASE_BLACK"]
        elif base == "BASE_SILVER":
            assert ok(rig.task("discard"))                            # anywhere: let go where it stands
            assert rig.held() is None
        else:
            assert ok(rig.task("discard", machine="C-RS1", side="SLIDE"))
            assert [wp.base for wp in w.workpieces_at("C-RS1", "slide")] == ["BASE_RED"]
    assert ok(rig.task("discard"))                                    # nothing held: nothing to do
    assert w.collision_count == 0


def _grab_recovery(rig):
    tree = rig.agent.run.tree if rig.agent.run is not None else None
    return tree.find("grab with recoveries") if tree is not None else None


def test_a_missed_grab_is_retried_after_re_aligning():
    rig = SimTaskRig(grab_failure=1.0)
    try:
        seen = {}

        def heal(r):
            rec = _grab_recovery(r)
            if rec is None:
                return
            seen["history"] = list(rec.history)
            if rec.level > 0 and "level" not in seen:
                seen["level"] = rec.level
                robot = r.robot.robot
                robot.config = robot.config.with_options(grab_failure=0.0)   # the next close works
        rig.hooks.append(heal)
        rig.world.spawn_workpiece("C-BS", "output", "BASE_RED")
        res = rig.task("get_workpiece", machine="C-BS", side="OUTPUT")
        assert ok(res), res
        assert seen["level"] == 1                                      # re-align and retry, then it worked
        assert seen["history"] == ["action@0", "recovery1.1", "action@1"]
        assert rig.held().base == "BASE_RED"
        states = [TM.RobotStatus.State.Name(s.state) for s in rig.server.of("RobotStatus")]
        assert "RECOVERING" in states
    finally:
        rig.close()


def test_a_grab_that_never_works_ends_in_grab_failed():
    rig = SimTaskRig(grab_failure=1.0)
    try:
        levels = set()
        rig.hooks.append(lambda r: _grab_recovery(r) is not None and levels.add(_grab_recovery(r).level))
        rig.world.spawn_workpiece("C-BS", "output", "BASE_RED")
        res = rig.task("get_workpiece", machine="C-BS", side="OUTPUT")
        assert status(res) == "FAILED" and error(res) == "GRAB_FAILED"
        assert league_name(res.league_code) == "GRASPING_FAILED", res     # the workpiece was there
        assert levels == {0, 1, 2}                                   # both recovery levels ran
        assert not res.holding and rig.held() is None
        v = rig.robot.odometry()
        assert (v.vx, v.vy, v.omega) == (0.0, 0.0, 0.0)              # stopped
    finally:
        rig.close()


def test_a_grab_where_nothing_is_ends_in_no_workpiece_found(rig):
    """Nothing on the base station's output: every grab, after re-aligning and approaching
    again, finds nothing between the open fingers: the league's NO_WORKPIECE_FOUND (202),
    not GRASPING_FAILED."""
    assert rig.world.workpiece_at("C-BS", "output") is None
    res = rig.task("get_workpiece", machine="C-BS", side="OUTPUT")
    assert status(res) == "FAILED" and error(res) == "GRAB_FAILED" and not res.holding
    assert league_name(res.league_code) == "NO_WORKPIECE_FOUND", res
    assert res.text.startswith("no workpiece found"), res
