"""The 2025 field generator's constraints, as the referee box's solver states them.

The real refbox places the seven cyan machines with a constraint solver over
the 7 x 8 half (``src/libs/mps_placing_clips/mps_placing.h``; refbox-rules.md
"Field generation"); the magenta twins and the RS/CS swap follow as in every
rule set (:mod:`.layout`).  This module restates those constraints and draws
a random solution by randomised backtracking (the refbox branches on random
variables and values too).  Grid coordinates are the zone digits: x = 1..7
from the centre line, y = 1..8; x = 0 (the centre line), x = 8 and
y = 0, 9 are the border around the half.

- **Reserved zones.**  A machine takes its own zone and the zones in front of
  its sides: at 0/180 degrees the zones left and right (x +- 1), at 90/270
  above and below (y +- 1), at 45 degree rotations three zones on each side
  (both, and a corner).  The DS, used from its input only, reserves that
  side only (at 135 and 315 degrees its corner zone as the refbox code
  names it, which is the other diagonal).  No zone is taken twice; the
  border and centre line are reserved; so are the insertion zones (5,1),
  (6,1), (7,1), and (5,2) holds no machine.  Machines may stand in
  neighbouring zones and in column 1.
- **Orientation at the walls.**  Next to the bottom/top wall (y = 1 / 8) a BS
  or SS stands at 0 or 180 degrees, an RS or CS at 0 / 180; next to the side
  wall (x = 7) a BS/SS at 90 or 270, an RS/CS at 270; next to the centre
  line (x = 1) 90 or 270.  A DS faces away from a wall.  (6,2) and (7,2) hold
  no machine but a DS (the refbox states that constraint against the
  angle of the empty insertion zone below them).
- **No three in a line** (row, column or diagonal), **no locked corners**
  ((2,1)/(1,2), (2,8)/(1,7), (6,8)/(7,7), (6,2)/(7,3) not both), and fixed
  angles in the corners: (1,1) 135, (1,8) 315, (7,8) 135, (7,2) 45, (4,1) 45.
"""
from __future__ import annotations

import random

W, H = 7, 8
TYPES = ("BS", "CS1", "CS2", "RS1", "RS2", "SS", "DS")
SYMMETRIC, ASYMMETRIC, INPUT_ONLY = {"BS", "SS"}, {"CS1", "CS2", "RS1", "RS2"}, {"DS"}
ANGLES = (0, 45, 90, 135, 180, 225, 270, 315)
INSERTION = frozenset({(W, 1), (W - 1, 1), (W - 2, 1)})
NO_MACHINE = INSERTION | {(W - 2, 2)}
FIXED_ANGLE = {(1, 1): 135, (1, H): 315, (W, H): 135, (W, 2): 45, (W - 3, 1): 45}
LOCKS = (((2, 1), (1, 2)), ((2, H), (1, H - 1)), ((W - 1, H), (W, H - 1)), ((W - 1, 2), (W, 3)))

Placement = tuple[int, int, int]          # x, y, angle


class PlacementError(RuntimeError):
    """No placement satisfies the constraints (or none was found in time)."""


def reserved(kind: str, x: int, y: int, angle: int) -> set[tuple[int, int]]:
    """The zones ``kind`` at (x, y) with ``angle`` keeps free in front of its sides."""
    both = kind not in INPUT_ONLY
    out: set[tuple[int, int]] = set()
    if angle not in (0, 180):
        if both or angle > 180:
            out.add((x, y - 1))
        if both or angle < 180:
            out.add((x, y + 1))
    if angle not in (90, 270):
        if both or angle < 90 or angle > 270:
            out.add((x + 1, y))
        if both or 90 < angle < 270:
            out.add((x - 1, y))
    if angle in (45, 225):
        if both or angle == 45:
            out.add((x + 1, y + 1))
        if both or angle == 225:
            out.add((x - 1, y - 1))
    if angle in (135, 315):
        if both or angle == 315:
            out.add((x - 1, y + 1))
        if both or angle == 135:
            out.add((x + 1, y - 1))
    return out


def blocked(zone: tuple[int, int]) -> bool:
    """The border around the half, the centre line and the insertion zones."""
    x, y = zone
    return x <= 0 or x > W or y <= 0 or y > H or zone in INSERTION


def alone_ok(kind: str, x: int, y: int, angle: int) -> bool:
    """The constraints on one machine by itself."""
    if (x, y) in NO_MACHINE or not (1 <= x <= W and 1 <= y <= H):
        return False
    if FIXED_ANGLE.get((x, y), angle) != angle:
        return False
    if any(blocked(z) for z in reserved(kind, x, y, angle)):
        return False
    if kind in INPUT_ONLY:
        if y == 1 and angle in (225, 270, 315):
            return False
        if x == 1 and angle in (0, 45, 315):
            return False
        if x == W and angle in (135, 180, 225):
            return False
        return not ((x, y) == (W - 3, 1) and angle in (135, 180, 225))
    if y in (1, H):
        allowed = (0, 180) if kind in SYMMETRIC else ((0,) if y == 1 else (180,))
        if angle not in allowed:
            return False
    if x in (1, W):
        allowed = (90, 270) if kind in SYMMETRIC or x == 1 else (270,)
        if angle not in allowed:
            return False
    # the angle of the empty zone below (6,2) and (7,2) is never 0 or 180
    return not (y == 2 and x in (W - 1, W))


def together_ok(placed: dict[str, Placement]) -> bool:
    """The constraints between machines (``placed``: kind -> (x, y, angle))."""
    used: set[tuple[int, int]] = set()
    for kind, (x, y, a) in placed.items():
        mine = {(x, y)} | reserved(kind, x, y, a)
        if used & mine:
            return False
        used |= mine
    occupied = {(x, y): a for x, y, a in placed.values()}
    for (x, y) in occupied:
        for dx, dy in ((0, 1), (1, 0), (1, 1), (-1, 1)):
            if (x + dx, y + dy) in occupied and (x + 2 * dx, y + 2 * dy) in occupied:
                return False
    for a, b in LOCKS:
        if a in occupied and b in occupied:
            return False
    if "DS" in placed:            # a DS in the top row: the refbox constrains the bottom one
        x, y, _ = placed["DS"]
        if y == H and occupied.get((x, 1)) in (45, 90, 135):
            return False
    return True


def solve(rng: random.Random, tries: int = 200) -> dict[str, Placement]:
    """A random placement of the seven cyan machines: kind -> (x, y, angle).

    Each machine in turn (random order) takes a zone drawn uniformly among those
    where some angle still fits, then an angle drawn among those that fit;
    depth first, a dead end goes back a step.  (Over 200 real fields, 94 % had
    neighbouring machines and 72 % used column 1; these draws give about 83 %
    and 72 %: benchmarks/refbox_rules.py.)"""
    options: dict[str, dict[tuple[int, int], list[int]]] = {}
    for k in TYPES:
        by_zone: dict[tuple[int, int], list[int]] = {}
        for x in range(1, W + 1):
            for y in range(1, H + 1):
                angles = [a for a in ANGLES if alone_ok(k, x, y, a)]
                if angles:
                    by_zone[(x, y)] = angles
        options[k] = by_zone
    for _ in range(tries):
        order = list(TYPES)
        rng.shuffle(order)
        found = _search(order, {}, options, rng, [0])
        if found is not None:
            return found
    raise PlacementError(f"no 2025 placement found in {tries} tries")


def _search(order, placed, options, rng, steps, limit: int = 5000):
    if len(placed) == len(order):
        return dict(placed)
    kind = order[len(placed)]
    fitting = {}
    for zone, angles in options[kind].items():
        ok = []
        for a in angles:
            placed[kind] = (zone[0], zone[1], a)
            if together_ok(placed):
                ok.append(a)
        if ok:
            fitting[zone] = ok
    placed.pop(kind, None)
    zones = list(fitting)
    rng.shuffle(zones)
    for zone in zones:
        angles = fitting[zone][:]
        rng.shuffle(angles)
        for a in angles:
            steps[0] += 1
            if steps[0] > limit:
                return None
            placed[kind] = (zone[0], zone[1], a)
            found = _search(order, placed, options, rng, steps, limit)
            if found is not None:
                return found
            del placed[kind]
    return None


def valid(placement: dict[str, Placement]) -> list[str]:
    """Every constraint ``placement`` breaks (empty when it is a real field)."""
    bad = [f"{k} at {p}" for k, p in placement.items() if not alone_ok(k, *p)]
    if sorted(placement) != sorted(TYPES):
        bad.append(f"machines {sorted(placement)}")
    if not together_ok(placement):
        bad.append("zones taken twice, three in a line, a locked corner or the DS row rule")
    return bad
