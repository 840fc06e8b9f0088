"""Which side of a station its cap shelf and ring slide are on.

Fact (refbox-protocol.md, mirroring 2017+): the magenta twin of a cyan RS or CS
by a wall gets a fixed rotation "keeping its shelf/slide off the wall" (y = 8 ->
180, y in {1, 2} -> 0, x = 7 -> 270); the league's own skills put the shelf and the
slide on the right of a robot facing the input, that is machine +y.  With the
shelf on the other side (as before this test), the refbox's fixed rotations put
every such shelf against the wall: a robot in front of slot 0 overlapped it.
"""
import math

import pytest

from rll_bt.rules import profile
from rll_bt.rules.geometry import RobotGeometry


def _spot(p, zone: int, rotation: int, lateral: float) -> tuple[float, float]:
    """Where a robot stands to reach ``lateral`` (machine y) on the input side of a
    station in ``zone`` at ``rotation``: the face plus the robot's radius."""
    cx, cy = p.zones.centre(zone)
    th = math.radians(rotation)
    ahead = p.mps.depth / 2.0 + RobotGeometry().radius
    return (cx + ahead * math.cos(th) - lateral * math.sin(th),
            cy + ahead * math.sin(th) + lateral * math.cos(th))


@pytest.mark.parametrize("cyan_zone_name", ["C_Z38", "C_Z21", "C_Z62", "C_Z74"])
@pytest.mark.parametrize("machine", ["C-CS1", "C-RS2"])
def test_shelf_and_slide_of_a_twin_with_the_fixed_wall_rotation_are_off_the_wall(machine, cyan_zone_name):
    p = profile("rcll2025")
    zone, rotation = p.mirror_placement(machine, p.zones.number(cyan_zone_name), 0)
    assert not p.twin_mirrors(machine, p.zones.number(cyan_zone_name))
    field = p.field
    sides = [p.mps.shelf_y[0]] if "CS" in machine else [p.mps.slide_y]
    r = RobotGeometry().radius
    for lateral in sides:
        x, y = _spot(p, zone, rotation, lateral)
        # the robot in front of the farthest slot stays inside the walls with room to spare
        assert field.x_min + r + 0.05 < x < field.x_max - r - 0.05, (cyan_zone_name, x)
        assert y > r + 0.05 and y < field.y_max - r - 0.05, (cyan_zone_name, y)
