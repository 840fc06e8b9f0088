"""The sim backend with a world of its own: what `rll-bt tree run --backend sim`
and `rll-bt agent --backend sim` use."""
from __future__ import annotations

import json
import math

import pytest

from rll_bt.backend import open_backend
from rll_bt.cli import main
from rll_bt.clock import SimClock


def test_a_world_of_its_own_follows_the_callers_clock():
    clock = SimClock()
    robot = open_backend("sim", seed=3, clock=clock)
    try:
        world = robot.world
        start = robot.odometry().pose
        for _ in range(20):               # a controller re-sends its command (the base has a deadman)
            robot.drive(0.3, 0.0, 0.0)
            clock.advance(0.1)
        moved = robot.odometry().pose
        assert world.time == pytest.approx(2.0, abs=0.03)
        assert math.hypot(moved.x - start.x, moved.y - start.y) == pytest.approx(0.6, abs=0.1)
        robot.stop()
        clock.advance(100.0)          # a long pause is not simulated at once
        robot.odometry()
        assert world.time == pytest.approx(4.0, abs=0.03)
    finally:
        robot.close()
    assert not world.connected        # closing the robot closed its world


def test_the_profile_and_perception_options_build_the_world():
    robot = open_backend("sim", profile="rcll2025", seed=2, perception="rendered", clock=SimClock())
    try:
        assert robot.world.profile.name == "rcll2025" and robot.world.perception == "rendered"
        img = robot.camera_image()
        assert img.image.ndim == 3 and img.image.shape[2] == 3 and img.image.std() > 0
    finally:
        robot.close()


def test_tree_run_drives_a_tree_in_the_simulated_world(tmp_path, capsys):
    log = tmp_path / "ticks.jsonl"
    rc = main(["tree", "run", "-I", "trees", "trees/go_to.yaml", "--backend", "sim", "--backend-opt", "seed=3",
               "--start-pose", "3.5,-0.5,1.5708", "--task", "has_target=false", "--task", "zone=5",
               "--clock", "sim", "--timeout", "120", "-q", "--log", str(log)])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "go_to: SUCCESS" in out
    ticks = [json.loads(line) for line in log.read_text().splitlines()]
    assert ticks and any("navigate" in json.dumps(t) for t in ticks)


def test_tree_run_sim_with_a_bad_option_is_a_user_error(capsys):
    rc = main(["tree", "run", "-I", "trees", "trees/go_to.yaml", "--backend", "sim", "--backend-opt",
               "perception=xray", "--clock", "sim", "--max-ticks", "1", "-q"])
    assert rc == 2
    assert "perception" in capsys.readouterr().err
