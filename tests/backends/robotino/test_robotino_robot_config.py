"""The robot configuration file, the Robotino backends composing laser,
camera and gripper from it over emulated devices (real ptys and sockets),
``rll-bt robotino check``, and a laser pulled in the middle of an action."""
import json
import math
import time

import numpy as np
import pytest
import yaml

from backends.robotino.config import RobotConfigError, load_robot_config, parse_robot_config
from backends.robotino.rig import LASERS, EmulatedRobot
from backends.robotino_rest.standin import RestStandIn
from rll_bt import rules
from rll_bt.agent import TREE_KINDS, default_trees_dir, load_task_tree
from rll_bt.agenttask import read_task, render_task
from rll_bt.backend import Capability, Pose2D, SensorLost, open_backend
from rll_bt.cli import main
from rll_bt.clock import WallClock
from skills.context import SkillContext
from skills.errors import SkillError
from skills.navigation.motions import MoveRelative

#: one sample task per kind, as rll-bt's team server plans them
SAMPLES = {
    "explore_zone": dict(zone=6),
    "get_workpiece": dict(machine="C-CS1", side="SHELF", shelf_slot=1),
    "put_workpiece": dict(machine="C-RS1", side="SLIDE"),
    "retrieve_cap": dict(machine="C-CS1", shelf_slot=0),
    "mount_ring": dict(machine="C-RS1", ring_color="RING_GREEN"),
    "mount_cap": dict(machine="C-CS2", cap_color="CAP_BLACK"),
    "deliver": dict(machine="C-DS", gate=3),
    "discard": dict(),
    "go_to": dict(x=1.5, y=2.5, zone=5),
}
ALL = Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.CAMERA | Capability.GRIPPER


def _params(kind):
    """The tree parameters the agent reads from the AgentTask (+ TaskDetail) of ``kind``."""
    profile = rules.profile("rcll2016")
    at, detail = render_task(kind, SAMPLES[kind], task_id=1, robot_id=1, color="CYAN", profile=profile)
    return read_task(at, detail, profile=profile, robot_id=1, color="CYAN")[1]


@pytest.fixture(params=LASERS)
def rig(request):
    r = EmulatedRobot(laser=request.param, holding_sensor="distance:8>1.5").start()
    yield r
    r.stop()


def test_a_configuration_file_is_checked_against_its_schema(tmp_path):
    good = tmp_path / "robot.yaml"
    good.write_text("base: {type: robotino3, device: /dev/ttyACM0}\n"
                    "laser: {type: urg, device: /dev/ttyACM1, mount: {x: 0.1, yaw: 90, upside_down: true}}\n"
                    "camera: {source: /dev/video0, calibration: cam.yaml, mount: {z: 0.5, pitch: 20}}\n")
    cfg = load_robot_config(good)
    m = cfg.laser_mount()
    assert (m.x, m.yaw, m.upside_down) == (0.1, pytest.approx(math.pi / 2), True)
    assert cfg.camera_extrinsics().pitch == pytest.approx(math.radians(20))
    assert cfg.resolve("cam.yaml") == str(tmp_path / "cam.yaml")
    for text, message in [
        ("laser: {type: urg, device: /dev/x}\n", "'base' is a required property"),
        ("base: {type: robotino5}\n", "base/type"),
        ("base: {type: robotino3}\nlaser: {type: urg}\n", "'device' is a required property"),
        ("base: {type: robotino3}\nlaser: {type: tim}\n", "'host' is a required property"),
        ("base: {type: robotino3}\ncamera: {source: 0, colour: red}\n", "camera: Additional properties"),
        ("base: {type: robotino3\n", "not YAML"),
    ]:
        bad = tmp_path / "bad.yaml"
        bad.write_text(text)
        with pytest.raises(RobotConfigError, match=message) as exc:
            load_robot_config(bad)
        assert str(bad) in str(exc.value)


def test_a_configuration_file_that_is_not_utf8_text_is_a_clear_error(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_bytes(b"base: {type: robotino3, device: /dev/tty\xf8ACM0}\n")     # found by benchmarks/fuzz.py
    with pytest.raises(RobotConfigError, match="not UTF-8 text"):
        load_robot_config(path)


def test_every_shipped_tree_builds_on_the_robotino_backend_with_its_parts(rig):
    backend = open_backend("robotino", robot_config=rig.config())
    try:
        assert backend.capabilities == ALL | Capability.BUMPER | Capability.BATTERY
        _every_tree_builds(backend)
    finally:
        backend.close()


def test_every_shipped_tree_builds_on_a_robotino_4_with_the_same_parts():
    rig = EmulatedRobot(laser="urg").start()
    try:
        with RestStandIn() as robot4:
            cfg = rig.config()
            cfg["base"] = {"type": "robotino4", "url": robot4.url}
            backend = open_backend("robotino", robot_config=cfg)
            try:
                assert type(backend).__name__ == "RobotinoRestBackend"
                assert ALL & backend.capabilities == ALL
                scan = backend.laser_scan()
                assert len(scan.ranges) == 682 and scan.mount.x == pytest.approx(0.12)    # the URG, not /data/scan0
                _every_tree_builds(backend)
            finally:
                backend.close()
    finally:
        rig.stop()


def _every_tree_builds(backend):
    clock = WallClock()
    services = {"start_pose": Pose2D(1.0, 1.0, 0.0), "localisation": "cheap", "profile": "rcll2016"}
    for kind in TREE_KINDS:
        params = _params(kind)
        tree = load_task_tree(default_trees_dir(), kind, params, backend=backend, clock=clock,
                              services=dict(services))
        assert tree.nodes, kind


def test_scans_and_frames_arrive_through_the_backend(rig):
    opened = time.monotonic()
    backend = open_backend("robotino", robot_config=rig.config())
    try:
        scan = backend.laser_scan()
        assert np.allclose(scan.ranges[np.isfinite(scan.ranges)], rig.room)
        assert opened - 0.001 <= scan.stamp <= time.monotonic()            # on the host's clock
        frame = backend.camera_image()
        assert frame.image.shape == (240, 320, 3) and opened <= frame.stamp <= time.monotonic()
        assert frame.extrinsics.position == (0.2, 0.0, 0.6)
    finally:
        backend.close()


def _run(skill, liveness=120.0):
    """Poll ``skill`` until it ends (``liveness`` bounds a hang only); its status."""
    end = time.monotonic() + liveness
    while skill.poll().name == "RUNNING" and time.monotonic() < end:
        time.sleep(0.05)
    return skill.status


def test_the_laser_pulled_mid_action_stops_the_robot_and_fails_it_then_the_robot_goes_on(rig, wait_for):
    backend = open_backend("robotino", robot_config=dict(rig.config(), faults={"stale": 1.0}))
    clock = WallClock()
    try:
        ctx = SkillContext.create(backend, clock, rules.profile("rcll2016"), Pose2D(1.0, 1.0, 0.0),
                                  localisation=None)
        # driving before the cable is pulled (a machine that starved the laser's thread for 1 s already
        # failed that move with a lost laser: started again, a hang bounded by the liveness wait)
        end = time.monotonic() + 120.0
        while True:
            move = MoveRelative(ctx, 2.0, 0.0, speed=0.3).start()
            while move.poll().name == "RUNNING" and not any(rig.base.setpoints()[:3]):
                time.sleep(0.02)
            if move.poll().name == "RUNNING" or time.monotonic() > end:
                break
            wait_for(lambda: backend.parts.lost() is None, 10)
        assert move.poll().name == "RUNNING" and any(rig.base.setpoints()[:3])      # driving
        rig.unplug("laser", 2.5)
        _run(move)
        assert move.error is SkillError.SENSOR_LOST, move.message
        assert "laser lost" in move.message
        assert wait_for(lambda: not any(rig.base.wheel_speeds()[:3]), 2)          # the base stopped
        with pytest.raises(SensorLost):
            backend.drive(0.1, 0.0, 0.0)
        assert wait_for(lambda: backend.sensor_stops >= 1, 2)     # counted by the watch thread (every 20 ms)
        assert wait_for(lambda: backend.parts.lost() is None, 10)                # reopened by its driver
        again = MoveRelative(ctx, 0.1, 0.0, speed=0.2).start()
        assert _run(again).name == "SUCCESS", again.message
    finally:
        backend.close()


def _drives(backend):
    try:
        backend.drive(0.1, 0.0, 0.0)
    except SensorLost:
        return False
    return True


def test_a_camera_that_goes_silent_stops_the_robot_too(wait_for):
    rig = EmulatedRobot(laser=None).start()
    try:
        backend = open_backend("robotino", robot_config=dict(rig.config(), faults={"camera_stale": 0.6}))
        try:
            assert wait_for(lambda: _drives(backend), 2)        # a loaded machine may leave a device stale first
            rig.set_silent("camera", True)
            assert wait_for(lambda: backend.parts.lost() is not None, 3)
            with pytest.raises(SensorLost) as exc:
                backend.drive(0.1, 0.0, 0.0)
            assert exc.value.device == "camera"
            rig.set_silent("camera", False)
            assert wait_for(lambda: backend.parts.lost() is None, 10)
            assert wait_for(lambda: _drives(backend), 10)
        finally:
            backend.close()
    finally:
        rig.stop()


def test_robotino_check_reports_every_device(rig, tmp_path, capsys):
    path = rig.write_config(str(tmp_path / "robot.yaml"))
    assert main(["robotino", "check", "--robot-config", path, "--seconds", "0.5", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    devices = report["devices"]
    assert all(devices[n]["found"] for n in ("base", "laser", "camera", "gripper")), devices
    # rates as measured (how many a loaded machine reaches is the benchmarks' business), never above the devices'
    assert devices["base"]["rate_hz"] >= 0
    assert 0 <= devices["laser"]["rate_hz"] <= 1.1 / rig.laser_device.model.scan_period + 1
    assert devices["camera"]["rate_hz"] >= 0


def test_robotino_check_names_a_missing_device_and_exits_3(rig, tmp_path, capsys):
    cfg = rig.config()
    cfg["laser"] = {"type": "tim", "host": "127.0.0.1", "port": 9}          # nobody listens there
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(cfg))
    assert main(["robotino", "check", "--robot-config", str(path), "--seconds", "0.2", "--timeout", "1"]) == 3
    out = capsys.readouterr().out
    assert "laser    MISSING" in out and "127.0.0.1:9" in out and "missing: laser" in out
    assert "base     found" in out and "camera   found" in out


def test_robotino_check_with_a_bad_file_exits_2(tmp_path, capsys):
    path = tmp_path / "robot.yaml"
    path.write_text("base: {type: robotino3}\nlaser: {type: urg}\n")
    assert main(["robotino", "check", "--robot-config", str(path)]) == 2
    assert "'device' is a required property" in capsys.readouterr().err


def test_the_config_parser_takes_a_dict():
    cfg = parse_robot_config({"base": {"type": "robotino4"}})
    assert cfg.base["url"] == "http://127.0.0.1" and cfg.laser is None


def test_an_ethernet_urg_is_configured_by_its_address():
    from backends.robotino.parts import make_laser
    clock = WallClock()
    cfg = parse_robot_config({"base": {"type": "robotino3"}, "laser": {"type": "urg", "host": "192.168.0.10"}})
    assert make_laser(cfg, clock).device == "socket://192.168.0.10:10940"          # Hokuyo's port
    cfg = parse_robot_config({"base": {"type": "robotino3"},
                              "laser": {"type": "urg", "host": "10.0.0.5", "port": 10941, "mode": "poll"}})
    laser = make_laser(cfg, clock)
    assert (laser.device, laser.mode) == ("socket://10.0.0.5:10941", "poll")
    assert make_laser(parse_robot_config({"base": {"type": "robotino3"}, "laser": {"type": "tim", "host": "h"}}),
                      clock).describe().endswith("h:2112")


def test_rll_bt_sim_offers_the_rigs_lasers():
    """``rll-bt sim --laser`` names the rig's lasers (games reach backends by entry points only)."""
    from games.options import LASERS as OFFERED
    assert OFFERED == LASERS
