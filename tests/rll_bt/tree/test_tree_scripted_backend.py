"""The scripted backend replays readings on its clock and records commands."""
import pytest

from rll_bt.backend import BackendError, Capability, CapabilityError, open_backend
from rll_bt.clock import SimClock

SCRIPT = {
    "capabilities": ["drive", "odometry", "gripper"],
    "readings": {"holding": [{"t": 0, "value": False}, {"t": 2.0, "value": True}]},
    "faults": [{"method": "gripper_close", "call": 2, "message": "jammed"}],
}


def test_readings_follow_the_clock_and_commands_are_recorded(tmp_path):
    import yaml
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(SCRIPT))
    clock = SimClock()
    with open_backend("scripted", script=str(path), clock=clock) as robot:
        assert robot.capabilities == Capability.DRIVE | Capability.ODOMETRY | Capability.GRIPPER
        assert robot.holding() is False
        robot.drive(0.5, 0.0, 0.0)
        clock.advance(2.0)
        assert robot.holding() is True
        assert robot.odometry().pose.x == pytest.approx(1.0)    # integrated drive command
        robot.gripper_close()
        with pytest.raises(BackendError, match="jammed"):
            robot.gripper_close()
        with pytest.raises(CapabilityError):
            robot.bumper()
    assert [m for _, m, _ in robot.commands] == ["drive", "gripper_close", "gripper_close!", "stop", "close"]
    assert robot.calls("drive") == [(0.5, 0.0, 0.0)]


def test_bad_scripts_are_reported(tmp_path):
    with pytest.raises(BackendError, match="not found"):
        open_backend("scripted", script=str(tmp_path / "none.yaml"))
    with pytest.raises(BackendError, match="unknown capability"):
        open_backend("scripted", capabilities=["teleport"])


def test_a_capability_it_cannot_script_is_refused():
    """Advertising a laser it has no scans for would break the backend contract."""
    with pytest.raises(BackendError, match="cannot script laser or camera readings"):
        open_backend("scripted", capabilities=["drive", "laser", "camera"])
