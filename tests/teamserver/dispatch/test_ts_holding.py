"""Robots are not left holding a new base while its next step waits: a base whose cap
nobody can retrieve yet is not fetched, and of two pickups at the BS the base a ring
costs (put on the slide at once) goes before the product's own base."""
from teamserver.knowledge import model as M
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, production_setup

ALONE = ServerConfig(prefill_caps=False)      # one product's steps, no caps retrieved ahead


def _assigned(kb, **where):
    return [t for t in kb.tasks.values() if t.state == M.ASSIGNED and t.kind != M.GO_TO      # (parking)
            and all(getattr(t, k) == v for k, v in where.items())]


def test_a_base_whose_cap_nobody_can_retrieve_yet_is_not_fetched():
    ls = Lockstep(robots=2, config=ALONE)
    production_setup(ls, [{"id": 1}], states={"C-CS2": "DOWN"})      # its cap station is DOWN
    kb = ls.server.kb
    ls.step(n=5)
    [get] = [t for t in kb.tasks.values() if t.machine == "C-BS"]
    assert get.state == M.PENDING and not _assigned(kb)                # nobody holds a base for 60 s
    assert ls.server.dispatcher.holding.premature(get, 0.0)
    ls.station_states["C-CS2"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    ls.step(n=3)
    # the station is back: the cap retrieval and the base go out together, to the two robots
    assert {t.kind for t in _assigned(kb)} == {M.GET_WORKPIECE, M.RETRIEVE_CAP}
    assert {t.robot for t in _assigned(kb)} == {1, 2}


def test_the_base_a_ring_costs_is_fetched_before_the_products_own_base():
    """A C1 order whose blue ring costs two bases (one from the BS, one the cap-less base
    its cap retrieval frees): robot 2 goes for the cap, robot 1 to the BS, where it fetches
    the base for the slide (put at once), not the product's own base (held until the
    slide is stocked), though that one was planned first."""
    ls = Lockstep(robots=2, config=ALONE)
    production_setup(ls, [{"id": 1, "complexity": 1, "rings": ["RING_BLUE"]}])
    kb, holding = ls.server.kb, ls.server.dispatcher.holding
    ls.step(n=5)
    pickups = sorted((t for t in kb.tasks.values() if t.machine == "C-BS"), key=lambda t: t.id)
    assert len(pickups) == 2                                           # the product's base and the ring's
    own, for_slide = pickups
    assert holding.blocks(own, 0.0) and not holding.blocks(for_slide, 0.0)
    assert not holding.premature(own, 0.0)         # (what its ring waits for is under way)
    assert for_slide.state == M.ASSIGNED and for_slide.robot == 1 and own.state == M.PENDING
    assert [t.robot for t in _assigned(kb, kind=M.RETRIEVE_CAP)] == [2]
