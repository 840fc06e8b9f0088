"""Production policy of the team server, step by step: deliveries the refbox never
counted, caps retrieved ahead and when a cap is due, places the robots keep failing
at, and the planner option (HTN or the greedy baseline)."""
import pytest

from rll_bt import msgs
from rll_bt.cli import main
from rll_bt.clock import SimClock
from rll_bt.comm import MessageRegistry
from rll_bt.contracts import TeamServerOptions
from teamserver.cli import PLANNER_NAMES
from teamserver.game import InProcessTeamServer
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from teamserver.planning.planner import PLANNERS, GreedyPlanner, ProductionPlanner, make_planner
from teamserver.production.caps import FREE
from teamserver.production.health import StationHealth
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, abandon_all_products, play, production_setup


def test_a_delivery_the_refbox_never_counted_opens_its_order_again():
    ls = Lockstep()
    production_setup(ls, [{"id": 1}, {"id": 3, "quantity_requested": 2}])
    pm, kb = ls.server.production, ls.server.kb
    abandon_all_products(ls.server)
    kb.save_product(M.Product("D1", 1, state="DELIVERED", delivered_at=100.0))
    kb.save_product(M.Product("D2", 3, state="DELIVERED", delivered_at=100.0))
    kb.save_product(M.Product("A1", 3))
    w = pm.world.build(110.0, 900.0)
    assert w.in_progress == {1: 1, 3: 2} and w.making == 1 and w.slots == 2
    w = pm.world.build(130.0, 900.0)            # 30 s on, the refbox counted neither
    assert w.in_progress == {3: 1} and w.slots == 2
    assert {c.order.id for c in pm.planner.candidates(w)} == {1, 3}


def test_caps_are_retrieved_ahead_and_mounted_by_the_next_product():
    ls = Lockstep()
    production_setup(ls, [{"id": 1}])                       # black caps (C-CS2) only
    pm, kb = ls.server.production, ls.server.kb
    [ahead] = [p for p in kb.products.values() if p.order_id == 0]
    kinds = [(t.kind, t.machine) for t in kb.tasks_of(ahead.tasks)]
    assert kinds == [(M.RETRIEVE_CAP, "C-CS1"), (M.GET_WORKPIECE, "C-CS1"), (M.DISCARD, None)]
    assert pm.caps.prefill(5.0, 900.0) == []                       # one at a time
    assert play(ls, lambda gt: pm.buffers.owners.get("C-CS1") == FREE and ahead.state != "ACTIVE"
                and kb.products[ahead.id].state == "DELIVERED")
    assert not pm.locks.owners.get("C-CS1") and not pm.locks.owners.get("C-CS1#cap")
    # a grey order comes: its product mounts the cap that waits, it retrieves none
    bc, cc = ls.refbox.ms.enum("BaseColor"), ls.refbox.ms.enum("CapColor")
    ls.order_msgs.append(dict(ls.order_msgs[0], id=2, delivery_gate=2,
                              base_color=bc.Value("BASE_BLACK"), cap_color=cc.Value("CAP_GREY")))
    ls.refbox.orders(ls.order_msgs)
    ls.step(n=3)
    [grey] = [p for p in kb.products.values() if p.order_id == 2]
    steps = kb.tasks_of(grey.tasks)
    assert {t.state for t in steps if t.kind == M.RETRIEVE_CAP} == {M.CANCELLED}
    assert [t.machine for t in steps if t.kind == M.MOUNT_CAP] == ["C-CS1"]
    assert pm.buffers.owners["C-CS1"] == grey.id


def test_no_cap_is_retrieved_ahead_without_orders_or_near_the_end():
    ls = Lockstep()
    production_setup(ls, [])
    pm = ls.server.production
    assert pm.caps.prefill(10.0, 900.0) == []                      # nothing to make yet
    production_setup(ls, [{"id": 1}])
    assert pm.caps.prefill(850.0, 900.0) == []


def test_a_cap_is_retrieved_once_the_ring_mounts_before_it_are_under_way():
    ls = Lockstep()
    # two rings that cost nothing: no cap-less base is needed, so the cap comes last
    production_setup(ls, [{"id": 6, "complexity": 2, "rings": ["RING_GREEN", "RING_YELLOW"]}])
    kb, pm = ls.server.kb, ls.server.production
    [p] = [p for p in kb.products.values() if p.order_id == 6]
    [retrieve] = [t for t in kb.tasks_of(p.tasks) if t.kind == M.RETRIEVE_CAP]
    mounts = [t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_RING]
    assert not pm.caps.cap_due(retrieve) and not ls.server.dispatcher.readiness.ready(retrieve, 1.0)
    mounts[0].state = M.DONE
    kb.save_task(mounts[0])
    assert not pm.caps.cap_due(retrieve)
    mounts[1].state = M.ASSIGNED
    kb.save_task(mounts[1])
    assert pm.caps.cap_due(retrieve)


def test_a_cap_that_feeds_a_slide_is_retrieved_at_once():
    ls = Lockstep()
    # BLUE costs two bases: one of them is the cap-less base of the cap retrieval
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}])
    kb = ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 5]
    [retrieve] = [t for t in kb.tasks_of(p.tasks) if t.kind == M.RETRIEVE_CAP]
    assert ls.server.production.caps.cap_due(retrieve)


def test_a_place_that_keeps_failing_is_paused_and_a_success_clears_the_count():
    clock = SimClock()
    kb = KnowledgeBase(__import__("rll_bt").rules.profile("rcll2016"))
    h = StationHealth(kb, max_failures=3, pause=100.0)
    slide = M.Task(1, M.PUT_WORKPIECE, {"machine": "C-RS2", "side": M.SLIDE})
    out = M.Task(2, M.GET_WORKPIECE, {"machine": "C-RS2", "side": M.OUTPUT})
    bs = M.Task(3, M.GET_WORKPIECE, {"machine": "C-BS", "side": M.OUTPUT})
    assert not h.outcome(slide, False, "NAVIGATION_FAILED", clock.now())
    assert not h.outcome(slide, False, "CANCELLED", clock.now())      # says nothing
    assert not h.outcome(slide, True, "NONE", clock.now())            # count cleared
    assert not h.outcome(slide, False, "TIMEOUT", clock.now())
    assert not h.outcome(slide, False, "TIMEOUT", clock.now())
    assert h.outcome(slide, False, "ALIGN_FAILED", clock.now())
    assert h.unusable(clock.now()) == {"C-RS2:SLIDE"}
    assert h.usable(out, clock.now()) and not h.usable(slide, clock.now())
    for _ in range(5):
        h.outcome(bs, False, "GRAB_FAILED", clock.now())              # never the BS
    assert h.usable(bs, clock.now())
    clock.advance(101.0)
    assert h.unusable(clock.now()) == frozenset()


def test_the_planner_is_an_option_of_the_server():
    assert tuple(PLANNERS) == PLANNER_NAMES
    ls = Lockstep(config=ServerConfig(planner="greedy"))
    production_setup(ls, [{"id": 1}, {"id": 2, "delivery_gate": 2}])
    assert isinstance(ls.server.planner, GreedyPlanner)
    assert ls.server.production.planner is ls.server.planner
    assert {p.order_id for p in ls.server.kb.products.values() if p.order_id} == {1}
    with pytest.raises(ValueError, match="unknown planner"):
        make_planner("astar", ls.server.profile, "C")
    assert type(make_planner("htn", ls.server.profile, "C")) is ProductionPlanner


def test_the_simulated_game_plays_the_baseline_through_the_option(tmp_path):
    ls = Lockstep()                        # a bus and registries to hand the factory
    reg = MessageRegistry.from_message_set(msgs.message_set("rcll2016"))
    ts = InProcessTeamServer(
        profile="rcll2016", team_name="T", key="k", clock=ls.clock,
        refbox_public=lambda: ls.bus.peer("public", registry=reg, name="x"),
        refbox_team=lambda color: ls.bus.peer(color.lower(), registry=reg, name="x"),
        agents=lambda: ls.bus.stream_server("ts2", registry=ls.team_reg, key="k"),
        state=str(tmp_path / "ts.sqlite"), options=TeamServerOptions(baseline=True))
    assert ts.config.planner == "greedy" and ts.config.max_products == 1
    assert not ts.config.prefill_caps                   # no look-ahead
    assert isinstance(ts.server.planner, GreedyPlanner)
    ts.close()


def test_cli_offers_the_planner(capsys):
    with pytest.raises(SystemExit):
        main(["teamserver", "--help"])
    assert "--planner {htn,greedy}" in capsys.readouterr().out
    with pytest.raises(SystemExit) as bad:
        main(["teamserver", "--team", "X", "--key", "k", "--planner", "astar"])
    assert bad.value.code == 2


@pytest.mark.parametrize("order, rest", [
    ({"id": 2, "cap_color": 2}, M.DISCARD),                       # C0: the base was discarded
    ({"id": 5, "complexity": 1, "rings": ["RING_BLUE"], "cap_color": 2}, M.PUT_WORKPIECE),  # on a slide
])
def test_a_cap_retrieved_ahead_goes_to_a_product_planned_before_it(order, rest):
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    production_setup(ls, [order], states={"C-CS1": "DOWN"})     # grey cap (C-CS1)
    pm, kb = ls.server.production, ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == order["id"]]
    retrieve, pick, after = pm.caps.cap_chain(p, "C-CS1")
    ls.station_states["C-CS1"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    assert after.kind == rest
    pm.buffers.take("C-CS1", "free")                       # then a cap is retrieved ahead
    assert not ls.server.dispatcher.readiness.ready(retrieve, 1.0)  # the CS cannot retrieve another
    assert pm.caps.adopt_free_caps() == [p]
    assert pm.buffers.owners["C-CS1"] == p.id
    assert {kb.tasks[t.id].state for t in (retrieve, pick)} == {M.CANCELLED}
    [mount] = [t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_CAP]
    if rest == M.DISCARD:
        assert kb.tasks[after.id].state == M.CANCELLED and after.id not in mount.deps
    else:                                               # a base from the BS feeds the slide
        slide = kb.tasks[after.id]
        [get] = [kb.tasks[d] for d in slide.deps]
        assert get.machine == "C-BS" and slide.params["carry_from"] == get.id
        assert slide.state == M.PENDING and get.state == M.PENDING
    assert play(ls, lambda gt: kb.products[p.id].state == "DELIVERED")
    assert not [t for t in kb.tasks_of(p.tasks) if t.kind == M.RETRIEVE_CAP
                and t.state == M.DONE]


def test_a_place_paused_again_is_paused_twice_as_long():
    kb = KnowledgeBase(__import__("rll_bt").rules.profile("rcll2016"))
    h = StationHealth(kb, max_failures=2, pause=100.0)
    cs = M.Task(1, M.GET_WORKPIECE, {"machine": "C-CS1", "side": M.OUTPUT})
    for now in (0.0, 1.0):
        h.outcome(cs, False, "GRAB_FAILED", now)
    assert h.unusable(99.0) == {"C-CS1"} and not h.unusable(101.0)
    for now in (200.0, 201.0):
        h.outcome(cs, False, "GRAB_FAILED", now)
    assert h.unusable(390.0) == {"C-CS1"} and not h.unusable(402.0)


@pytest.mark.parametrize("rings, reused", [
    (("RING_GREEN", "RING_ORANGE"), True),     # the last ring costs a base: the cap-less one
    (("RING_ORANGE", "RING_GREEN"), False),    # only the first does: fetched from the BS
])
def test_the_cap_less_base_serves_only_the_last_ring(rings, reused):
    from rll_bt import rules
    from teamserver.planning.estimate import SimRobot
    from teamserver.planning.planner import World
    p16 = rules.profile("rcll2016")
    rs = {"C-RS1": ("RING_BLUE", "RING_GREEN"), "C-RS2": ("RING_ORANGE", "RING_YELLOW")}
    costs = {"RING_BLUE": 2, "RING_GREEN": 0, "RING_ORANGE": 1, "RING_YELLOW": 0}
    caps = {"C-CS1": "CAP_GREY", "C-CS2": "CAP_BLACK"}
    o = M.Order(6, 2, "BASE_RED", rings, "CAP_GREY", 1, 0, 0, 900, 1)
    w = World([o], [SimRobot("1", (4.5, -0.5), 0.0)], {}, rs, costs, caps, 0.0, 900.0)
    pl = ProductionPlanner(p16, "C")
    net = pl.decompose(pl.context(w, o))
    kinds = [s.fields["kind"] for s in net.steps]
    assert kinds.count(M.DISCARD) == (0 if reused else 1)
    assert kinds.count(M.PUT_WORKPIECE) == 1


def test_a_cap_waiting_ahead_is_not_given_to_a_product_far_from_its_cap():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    production_setup(ls, [{"id": 6, "complexity": 2, "rings": ["RING_GREEN", "RING_YELLOW"],
                               "cap_color": 2}], states={"C-CS1": "DOWN"})
    pm, kb = ls.server.production, ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 6]
    pm.buffers.take("C-CS1", FREE)
    assert pm.caps.adopt_free_caps() == []          # two rings to go: it would block C-CS1
    for t in kb.tasks_of(p.tasks):
        if t.kind == M.MOUNT_RING:
            t.state = M.DONE
            kb.save_task(t)
    assert pm.caps.adopt_free_caps() == [p] and pm.buffers.owners["C-CS1"] == p.id


def test_a_cap_ahead_no_robot_took_yet_gives_way_to_a_product_whose_cap_is_due():
    """The retrieval ahead into C-CS1 went back to the pool with the station's lock (its
    station went DOWN before the prepare, say).  A grey C0 comes, whose cap is due at
    once: the retrieval ahead is given up and its lock released, so the C0 retrieves
    its own cap instead of waiting for a robot to take the one ahead first."""
    ls = Lockstep()
    production_setup(ls, [{"id": 1}])                       # black caps (C-CS2) only
    pm, kb = ls.server.production, ls.server.kb
    [ahead] = [p for p in kb.products.values() if p.order_id == 0]
    [early] = [t for t in kb.tasks_of(ahead.tasks) if t.kind == M.RETRIEVE_CAP]
    assert early.machine == "C-CS1"
    robot = kb.robots.get(early.robot) if early.robot is not None else None
    if robot is not None:
        robot.task_id = None
        kb.save_robot(robot)
    early.state, early.robot = M.PENDING, None
    kb.save_task(early)
    pm.locks.acquire(early)
    assert pm.caps.yield_prefills() == []                  # nobody's cap is due at C-CS1
    bc, cc = ls.refbox.ms.enum("BaseColor"), ls.refbox.ms.enum("CapColor")
    ls.order_msgs.append(dict(ls.order_msgs[0], id=2, delivery_gate=2,
                              base_color=bc.Value("BASE_BLACK"), cap_color=cc.Value("CAP_GREY")))
    ls.refbox.orders(ls.order_msgs)
    ls.step(n=3)
    assert kb.products[ahead.id].state == "ABANDONED"
    assert {t.state for t in kb.tasks_of(ahead.tasks)} == {M.CANCELLED}
    [grey] = [p for p in kb.products.values() if p.order_id == 2]
    [own] = [t for t in kb.tasks_of(grey.tasks) if t.kind == M.RETRIEVE_CAP]
    assert own.machine == "C-CS1" and pm.locks.owners.get("C-CS1") in (None, grey.id)


def test_a_robot_without_work_retrieves_a_cap_ahead_for_a_product_whose_cap_is_not_due():
    """The BS is DOWN: the C2's first ring waits for a base, its cap (grey, C-CS1) is
    not due before its rings are under way, so the robots have nothing to do: a cap is
    retrieved ahead into C-CS1, which the C2 mounts once its cap is due."""
    ls = Lockstep()
    production_setup(ls, [{"id": 6, "complexity": 2, "rings": ["RING_GREEN", "RING_YELLOW"],
                               "cap_color": 2}], states={"C-BS": "DOWN"})
    pm, kb = ls.server.production, ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 6]
    retrieve, _, _ = pm.caps.cap_chain(p, "C-CS1")
    assert not pm.caps.cap_due(retrieve)

    def ahead_into(cs):
        return [q for q in kb.products.values() if q.order_id == 0 and any(
            t.kind == M.RETRIEVE_CAP and t.machine == cs for t in kb.tasks_of(q.tasks))]
    ls.step(dt=0.5, n=34)
    assert ahead_into("C-CS1")
    # the C2's own retrieval stays pending: the cap waiting ahead is its to take when due
    assert kb.tasks[retrieve.id].state == M.PENDING
    pm.buffers.take("C-CS1", FREE)
    for t in kb.tasks_of(p.tasks):
        if t.kind == M.MOUNT_RING:
            t.state = M.DONE
            kb.save_task(t)
    assert pm.caps.adopt_free_caps() == [p] and pm.buffers.owners["C-CS1"] == p.id
