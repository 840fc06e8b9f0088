"""A robot backend behind the world process (backends/remote, the process games): the
gripper's status crosses the link whole, the workpiece sensor's reading too."""
import json

import pytest

from backends.remote import codec
from rll_bt.backend import GripperState, GripperStatus


@pytest.mark.parametrize("sensed", [True, False, None])
def test_the_gripper_status_crosses_the_link_with_its_workpiece_sensor(sensed):
    st = GripperStatus(GripperState.IDLE, True, (0.05, 0.0, 0.5), False, "", sensed)
    assert codec.decode("gripper_status", json.loads(json.dumps(codec.encode(st)))) == st


def test_a_world_process_without_the_sensor_reads_as_none():
    old = {"state": "idle", "is_open": True, "position": [0.0, 0.0, 0.5], "holding": True, "message": ""}
    assert codec.decode("gripper_status", old).sensed is None
