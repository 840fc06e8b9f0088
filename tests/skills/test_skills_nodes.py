"""The skills as tree nodes: registration through the entry point, trees
from YAML driving the flat world, errors on the blackboard, interruption."""
import math

from py_trees.common import Status as TreeStatus

from rll_bt.backend import Pose2D
from rll_bt.tree import ERROR_CODE_KEY, RunContext, default_registry, load_tree
from skills.nodes import NODE_TYPES
from tests.support.skills_scene import Scene

GRAB_AND_PUT = """
name: grab_and_put
task:
  source: {type: str}
  target: {type: str}
root:
  sequence_with_memory:
    children:
      - localised: {min_confidence: 0.3}
      - grab: {machine: $task.source, side: OUTPUT, holding: $bb.holding}
      - put: {machine: $task.target, side: SLIDE}
"""


def tree_for(scene, text, task):
    ctx = RunContext(backend=scene.robot, clock=scene.world.clock, services={"skills": scene.ctx})
    return load_tree("inline.yaml", text=text, task=task, ctx=ctx)


def tick_until_done(scene, tree, limit=3000):
    for _ in range(limit):
        status = tree.tick()
        if status is not TreeStatus.RUNNING:
            return status
        scene.advance(0.1)
    return status


def test_every_skill_node_is_registered_through_the_entry_point():
    reg = default_registry()
    for cls in NODE_TYPES:
        nt = reg.get(cls.node_type)
        assert nt is not None and nt.cls is cls and nt.doc
        for port in nt.ports.values():
            assert port.doc, f"{nt.name}.{port.name} is undocumented"


def test_a_yaml_tree_grabs_and_puts():
    scene = Scene(seed=4)
    wp = scene.world.workpiece_at("C-BS", "OUTPUT")
    tree = tree_for(scene, GRAB_AND_PUT, {"source": "C-BS", "target": "C-RS1"})
    assert tick_until_done(scene, tree) is TreeStatus.SUCCESS
    assert tree.ctx.blackboard.get("/holding") is True
    assert wp.held_by is None and scene.world.collisions == 0


def test_a_failed_grab_fails_the_tree_with_its_error_code():
    scene = Scene(seed=4)
    tree = tree_for(scene, GRAB_AND_PUT, {"source": "C-BS", "target": "C-RS1"})   # nothing to grab
    assert tick_until_done(scene, tree) is TreeStatus.FAILURE
    bb = tree.ctx.blackboard
    assert bb.get(ERROR_CODE_KEY) == "GRAB_FAILED" and bb.get("/holding") is False


def test_interrupting_a_node_cancels_the_skill_and_stops_the_robot():
    scene = Scene(seed=4)
    text = """
root:
  navigate_to_pose: {goal: {x: -4.0, y: 2.5, theta: 0.0}}
"""
    tree = tree_for(scene, text, {})
    for _ in range(15):
        assert tree.tick() is TreeStatus.RUNNING
        scene.advance(0.1)
    assert any(scene.robot.cmd)
    tree.root.stop(TreeStatus.INVALID)
    assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0)


def test_explore_zone_node_reports_what_it_found():
    scene = Scene(seed=2, stations_in_map=False)
    seen = []
    scene.ctx.machines.subscribe(seen.append)
    text = """
root:
  explore_zone: {zone: Z9, want_light: false, found: $bb.found}
"""
    tree = tree_for(scene, text, {})
    assert tick_until_done(scene, tree) is TreeStatus.SUCCESS
    assert tree.ctx.blackboard.get("/found") == ["C-BS"]
    assert any(o.machine == "C-BS" and o.pose is not None for o in seen)


def test_bad_port_values_fail_the_node_not_the_runner():
    scene = Scene()
    tree = tree_for(scene, "root:\n  navigate_to_zone: {zone: Z99}\n", {})
    assert tick_until_done(scene, tree) is TreeStatus.FAILURE
    assert tree.ctx.blackboard.get(ERROR_CODE_KEY) == "INVALID_TASK"


def test_skills_service_is_built_from_the_run_context():
    scene = Scene(localisation=None)
    ctx = RunContext(backend=scene.robot, clock=scene.world.clock,
                     services={"start_pose": Pose2D(4.5, 2.0, math.pi / 2), "localisation": "cheap"})
    sctx = ctx.service("skills")
    assert sctx.pose().distance_to(Pose2D(4.5, 2.0)) < 1e-9
    assert sctx.profile.name == "rcll2016"


BLOCKING_CASES = {
    "navigate_to_pose": "{goal: {x: -4.0, y: 2.5, theta: 0.0}}",
    "navigate_to_zone": "{zone: 9}",
    "navigate_to_station": "{machine: C-RS1, side: INPUT}",
    "explore_zone": "{zone: 9}",
    "approach_station": "{machine: C-BS, side: OUTPUT}",
    "grab": "{machine: C-BS, side: OUTPUT}",
    "put": "{machine: C-RS1, side: SLIDE}",
    "back_off": "{distance: 0.3}",
    "turn": "{angle: 1.5}",
    "relocalise": "{global_search: true}",
    "grab_from_shelf": "{machine: C-CS1}",
}


def test_no_skill_node_waits_inside_a_tick(monkeypatch):
    """A node starts its skill and returns at once: on a clock that does not
    move, every action node answers RUNNING tick after tick, and nothing in
    a tick sleeps (a sleep would hold up the whole tree and the agent)."""
    import time as time_module

    def no_sleep(seconds):
        raise AssertionError(f"a tick slept {seconds} s")

    default_registry()                # names the node classes (registration sets node_type)
    action_types = {cls.node_type for cls in NODE_TYPES} - {"localised", "holding_workpiece"}
    assert action_types == set(BLOCKING_CASES)          # a new action node needs a case here
    for node_type, ports in BLOCKING_CASES.items():
        scene = Scene(seed=4)
        tree = tree_for(scene, f"root:\n  {node_type}: {ports}\n", {})
        monkeypatch.setattr(time_module, "sleep", no_sleep)
        t0 = scene.world.clock.now()
        for _ in range(5):
            assert tree.tick() is TreeStatus.RUNNING, node_type
        monkeypatch.undo()
        assert scene.world.clock.now() == t0, f"{node_type} moved the clock inside a tick"
        tree.root.stop(TreeStatus.INVALID)
        assert tuple(scene.robot.cmd) == (0.0, 0.0, 0.0), f"{node_type} left the robot driving"
