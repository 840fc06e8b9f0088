"""2025: production goes on beside exploration's tail.  Exploration runs inside
PRODUCTION until every own station is reported; once the base, delivery and a cap
station are, one robot per station still unfound keeps exploring and the others
produce, with no step at (nor any product needing) a station not found yet."""
from teamserver.knowledge import model as M
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, machines_known
from tests.teamserver.production.test_ts_storage import COSTS, Stations2025, send_orders

T = 20.0        # game time: inside the 2025 exploration window
#: the cyan stations of the 2025 field of seed 1 (`rll-bt sim --profile rcll2025 --seed 1`)
ZONES25 = {"C-BS": 22, "C-CS1": 1073, "C-CS2": 45, "C-DS": 16, "C-RS1": 14, "C-RS2": 1076, "C-SS": 58}


def _exploring_with(unfound: tuple[str, ...]):
    ls = Lockstep("rcll2025", config=ServerConfig(prefill_caps=False))
    machines_known(ls, {m: z for m, z in ZONES25.items() if m not in unfound}, COSTS, T)
    ls.stations = Stations2025(ls)
    ls.stations._send()
    _wait(ls, 2)                                    # a report is due every second
    assert ls.server.refbox.exploring() and ls.server.explorer.active()
    return ls


def _wait(ls, seconds):
    """``seconds`` of game with the robots' heartbeats."""
    for _ in range(seconds):
        for a in ls.agents:
            a.beat()
        ls.step(n=10)


def _zones_done(ls):
    """Every robot finishes the zone it explores (the strategy may give it another)."""
    for t in _open(ls, M.EXPLORE_ZONE):
        next(a for a in ls.agents if a.number == t.robot).result(t.id)
    _wait(ls, 1)


def _open(ls, kind=None):
    return [t for t in ls.server.kb.tasks.values() if t.state == M.ASSIGNED
            and (kind is None or t.kind == kind)]


def test_one_robot_explores_for_the_storage_station_and_the_others_make_a_c0():
    ls = _exploring_with(("C-SS",))
    send_orders(ls, [{"id": 3, "delivery_period_begin": int(T) + 200,
                      "delivery_period_end": int(T) + 500}])
    _wait(ls, 2)
    assert ls.server.explorer.unfound() == {"C-SS"}
    _zones_done(ls)                     # the robots exploring when the DS was found go on
    explorers = _open(ls, M.EXPLORE_ZONE)
    work = [t for t in _open(ls) if t.kind in (M.GET_WORKPIECE, M.RETRIEVE_CAP)]
    assert len(explorers) == 1, "one robot looks for the one station not found"
    assert work, "the other robots produce"
    assert {t.robot for t in work}.isdisjoint({t.robot for t in explorers})
    assert all(t.machine != "C-SS" for t in ls.server.kb.tasks.values())
    assert ls.server.explorer.active()              # still exploring, still reporting


def test_nothing_is_made_that_needs_a_ring_station_not_found_yet():
    # C-RS1 (orange, green) and C-RS2 (blue, yellow): a C1 with a green ring needs C-RS1
    ls = _exploring_with(("C-RS1",))
    rc = ls.refbox.ms.enum("RingColor")
    send_orders(ls, [{"id": 4, "complexity": 1, "ring_colors": [rc.Value("RING_GREEN")],
                      "delivery_period_begin": int(T) + 200, "delivery_period_end": int(T) + 600}])
    _wait(ls, 2)
    planned = [t for t in ls.server.kb.tasks.values() if t.product is not None]
    assert any(t.machine == "C-RS1" for t in planned), "the C1 is planned"
    assert not [t for t in _open(ls) if t.product is not None], "but none of its steps goes"
    ls.agents[0].observe("C-RS1", zone=ZONES25["C-RS1"], zconf=0.99)
    _wait(ls, 2)
    assert not ls.server.explorer.active()          # everything reported: exploration is over
    assert [t for t in _open(ls) if t.product is not None], "found: the C1 goes"


def test_without_a_base_station_every_robot_explores():
    ls = _exploring_with(("C-BS",))
    send_orders(ls, [{"id": 3, "delivery_period_begin": int(T) + 200,
                      "delivery_period_end": int(T) + 500}])
    _wait(ls, 2)
    assert not ls.server.explorer.beside()
    assert len(_open(ls, M.EXPLORE_ZONE)) == len(ls.agents)
    assert not [t for t in _open(ls) if t.kind != M.EXPLORE_ZONE]
