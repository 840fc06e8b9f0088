"""The 2025 storage station as the real refbox plays it: six C0 products in it at the start,
-5 for every store and every retrieve, relocation when a back place is blocked."""
from __future__ import annotations

import pytest

from backends.sim.refbox import SSInstruction, Workpiece
from rll_bt.rules import CYAN, MAGENTA, MPS_TIMES

T = MPS_TIMES
PRESTORED = {(0, 1): ("BASE_RED", "CAP_GREY"), (1, 1): ("BASE_RED", "CAP_BLACK"),
             (2, 1): ("BASE_SILVER", "CAP_GREY"), (3, 1): ("BASE_SILVER", "CAP_BLACK"),
             (4, 1): ("BASE_BLACK", "CAP_GREY"), (5, 1): ("BASE_BLACK", "CAP_BLACK")}


def open_2025(harness25, **kw):
    return harness25(exploration=0, **kw).production()


def test_every_storage_station_starts_with_six_c0_products(harness25):
    h = harness25()
    for ss in ("C-SS", "M-SS"):
        st = h.station(ss)
        assert {k: (wp.base, wp.cap) for k, wp in st.stored().items()} == PRESTORED
        assert all(not wp.rings for wp in st.stored().values())
        assert st.place(0, 1).description == "BASE_RED CAP_GREY"


def test_storing_and_retrieving_cost_5_each(harness25):
    h = open_2025(harness25)
    g = h.game
    ss = h.station("C-SS")
    wp = Workpiece("BASE_RED", (), "CAP_BLACK")
    g.prepare(CYAN, "C-SS", SSInstruction("STORE", 0, 0), CYAN)
    h.world.put("C-SS", "input", wp)
    h.run(30)
    assert ss.stored()[(0, 0)] == wp and h.award_sum(CYAN) == -5
    g.prepare(CYAN, "C-SS", SSInstruction("RETRIEVE", 0, 0), CYAN)
    h.run(25)
    assert h.world.workpiece_at("C-SS", "output") == wp and h.award_sum(CYAN) == -10
    assert [e.reason for e in h.awards(CYAN)] == ["payment for storing (0, 0) at C-SS",
                                                  "payment for retrieving (0, 0) from C-SS"]


def test_a_prestored_c0_is_retrieved_in_21_s_for_5_points(harness25):
    h = open_2025(harness25)
    g = h.game
    g.prepare(MAGENTA, "M-SS", SSInstruction("RETRIEVE", 4, 1), MAGENTA)
    h.run(T.retrieve + 0.25)
    assert h.world.workpiece_at("M-SS", "output") == Workpiece("BASE_BLACK", (), "CAP_GREY")
    assert h.award_sum(MAGENTA) == -5 and (4, 1) not in h.station("M-SS").stored()


def test_a_back_place_behind_a_filled_one_is_reached_by_relocating_first(harness25):
    """production-ss-simple-relocate-start: the front workpiece goes to a free place the arm
    reaches (17.5 s), then the retrieve (17.5 s + the belt)."""
    h = open_2025(harness25)
    g = h.game
    ss = h.station("C-SS")
    front = Workpiece("BASE_SILVER", ("RING_BLUE",), None)
    ss.put_in_storage(2, 0, front)
    assert not ss.accessible(2, 1)
    g.prepare(CYAN, "C-SS", SSInstruction("RETRIEVE", 2, 1), CYAN)
    assert ss.state == "PROCESSING" and ss.moving[0] == (2, 0)
    h.run(17.75)
    assert (2, 0) not in ss.stored() and front in ss.stored().values()
    dest = next(k for k, w in ss.stored().items() if w == front)
    assert ss.accessible(*dest) and ss.state == "PROCESSING"
    h.run(T.retrieve)
    assert h.world.workpiece_at("C-SS", "output") == Workpiece("BASE_SILVER", (), "CAP_GREY")
    assert h.award_sum(CYAN) == -5                          # relocating costs nothing
    assert not [e for e in h.events("machine") if e.data["state"] == "BROKEN"]


def test_relocation_when_only_back_places_are_free_and_a_full_storage_breaks(harness25):
    h = open_2025(harness25)
    g = h.game
    ss = h.station("C-SS")
    for shelf in range(6):                       # every front place filled
        for slot in (0, 2, 4, 6):
            ss.put_in_storage(shelf, slot, Workpiece("BASE_RED"))
    wp = Workpiece("BASE_BLACK", (), "CAP_BLACK")
    g.prepare(CYAN, "C-SS", SSInstruction("STORE", 3, 3), CYAN)     # behind (3, 2)
    assert ss.state == "PROCESSING" and ss.moving[1][1] % 2 == 1     # a front one moves back
    h.run(17.75)
    assert ss.moving is not None                                     # then (3, 2) moves there
    h.run(17.5)
    assert ss.step == "input" and ss.state == "PROCESSING"
    h.world.put("C-SS", "input", wp)
    h.run(25)
    assert ss.stored()[(3, 3)] == wp and ss.state == "IDLE"
    for shelf in range(6):                       # now fill every place
        for slot in range(8):
            if not ss.place(shelf, slot).filled:
                ss.put_in_storage(shelf, slot, Workpiece("BASE_RED"))
    ss.shelf.pop((5, 1))
    assert g.prepare(CYAN, "C-SS", SSInstruction("STORE", 5, 1), CYAN) == "broken"
    assert ss.broken_cause == "storage-full"
    assert "inaccessible slot while the storage is full" in ss.broken_reason


@pytest.mark.parametrize("op", ["STORE", "RETRIEVE"])
def test_a_storage_station_prepared_for_a_store_waits_at_most_20_s(harness25, op):
    h = open_2025(harness25)
    g = h.game
    g.prepare(CYAN, "C-SS", SSInstruction(op, 0, 0 if op == "STORE" else 1), CYAN)
    h.run(21)
    st = h.station("C-SS")
    assert (st.state == "BROKEN") == (op == "STORE")
