"""The 2025 field generator's placement constraints (the real refbox's solver,
refbox-rules.md "Field generation"), on drawn fields and on fields built to break them."""
from __future__ import annotations

import random

import pytest

from backends.sim import placing2025 as P
from backends.sim.layout import generate_layout
from rll_bt.rules import profile

P25 = profile("rcll2025")


def fields(n=300, seed=4):
    rng = random.Random(seed)
    return [P.solve(rng) for _ in range(n)]


def test_drawn_fields_keep_every_constraint():
    for f in fields():
        assert P.valid(f) == []
        taken = [z for k, (x, y, a) in f.items() for z in {(x, y)} | P.reserved(k, x, y, a)]
        assert len(taken) == len(set(taken))                        # no zone used twice
        assert not any(P.blocked(z) for z in taken)                # border, centre, insertion
        assert not {(x, y) for x, y, _ in f.values()} & {(5, 1), (6, 1), (7, 1), (5, 2)}


def test_neighbours_and_column_1_occur_as_in_real_fields():
    fs = fields()
    neighbours = sum(any(abs(a[0] - b[0]) <= 1 and abs(a[1] - b[1]) <= 1
                         for i, a in enumerate(f.values()) for b in list(f.values())[i + 1:])
                     for f in fs)
    column1 = sum(any(x == 1 for x, _, _ in f.values()) for f in fs)
    assert neighbours / len(fs) > 0.3 and column1 / len(fs) > 0.2


def test_the_zones_in_front_of_inputs_and_outputs():
    assert P.reserved("RS1", 3, 4, 0) == {(4, 4), (2, 4)}
    assert P.reserved("BS", 3, 4, 90) == {(3, 5), (3, 3)}
    assert P.reserved("CS2", 3, 4, 45) == {(3, 3), (3, 5), (4, 4), (2, 4), (4, 5), (2, 3)}
    assert P.reserved("DS", 3, 4, 0) == {(4, 4)}                  # the input side only
    assert P.reserved("DS", 3, 4, 45) == {(3, 5), (4, 4), (4, 5)}
    assert P.reserved("DS", 3, 4, 270) == {(3, 3)}


@pytest.mark.parametrize("kind,zone,angle,ok", [
    ("RS1", (3, 1), 0, True), ("RS1", (3, 1), 180, False),       # RS/CS by the bottom wall: 0
    ("RS1", (3, 8), 180, True), ("RS1", (3, 8), 0, False),
    ("BS", (3, 1), 180, True), ("BS", (3, 1), 90, False),        # BS/SS: 0 or 180
    ("CS1", (7, 4), 270, True), ("CS1", (7, 4), 90, False),      # by the side wall: 270
    ("SS", (7, 4), 90, True),
    ("RS2", (1, 4), 90, True), ("RS2", (1, 4), 0, False),        # column 1: 90 or 270
    ("DS", (1, 4), 90, True), ("DS", (1, 4), 0, False),          # a DS there: 90 or 270
    ("DS", (1, 4), 180, False),
    ("BS", (5, 2), 0, False), ("BS", (6, 2), 0, False), ("DS", (6, 2), 90, True),
    ("SS", (6, 1), 0, False), ("BS", (2, 2), 45, True),
])
def test_orientation_at_walls_and_the_entrance(kind, zone, angle, ok):
    assert P.alone_ok(kind, *zone, angle) == ok


def test_three_in_a_line_and_a_locked_corner_are_refused():
    base = {"BS": (2, 4, 90), "SS": (3, 4, 90)}
    assert P.together_ok(base)
    assert not P.together_ok({**base, "RS1": (4, 4, 90)})          # a row of three
    assert P.together_ok({"RS1": (2, 1, 0)}) and not P.together_ok(
        {"RS1": (2, 1, 0), "RS2": (1, 2, 90)})                      # corner (2,1)/(1,2)


@pytest.mark.parametrize("seed", range(5))
def test_the_game_layout_is_a_real_field_with_mirrored_twins(seed):
    lay = generate_layout(P25, seed)
    drawn = {}
    for t in P25.machine_types:
        pl = lay["M-" + t] if t in lay.swapped else lay["C-" + t]    # where cyan was drawn
        x, y = P25.zones.digits(pl.zone)
        drawn[t] = (x, y, pl.rotation_deg)
    assert P.valid(drawn) == []
