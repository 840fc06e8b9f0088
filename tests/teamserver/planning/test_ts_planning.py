"""HTN production planning: decompositions for C0..C3 and every ring cost, repair
from partial progress, and the anytime choice of orders."""

import pytest

from rll_bt import rules
from rll_bt.clock import SimClock
from teamserver.knowledge import model as M
from teamserver.planning.domain import Progress
from teamserver.planning.estimate import SimRobot
from teamserver.planning.htn import Domain, Par, Planner, PlanningFailed, Seq
from teamserver.planning.planner import ProductionPlanner, World

P16 = rules.profile("rcll2016")
RS = {"C-RS1": ("RING_BLUE", "RING_GREEN"), "C-RS2": ("RING_ORANGE", "RING_YELLOW")}
CAPS = {"C-CS1": "CAP_GREY", "C-CS2": "CAP_BLACK"}
POS = {m: P16.zone_centre(z) for m, z in
       {"C-BS": 9, "C-DS": 4, "C-RS1": 2, "C-RS2": 7, "C-CS1": 11, "C-CS2": 6}.items()}


def world(orders, costs, robots=3, **kw):
    return World(orders, [SimRobot(str(i), (4.5, -0.5), 0.0) for i in range(1, robots + 1)],
                 POS, RS, costs, CAPS, now=kw.pop("now", 0.0), horizon=900.0, **kw)


def order(oid=1, rings=(), cap="CAP_BLACK", base="BASE_RED", begin=0, end=900):
    return M.Order(oid, len(rings), base, tuple(rings), cap, 1, 0, begin, end, 1)


def steps(net, kind, **params):
    return [i for i, s in enumerate(net.steps) if s.fields["kind"] == kind
            and all(s.fields["params"].get(k) == v for k, v in params.items())]


@pytest.mark.parametrize("complexity", [0, 1, 2, 3])
@pytest.mark.parametrize("cost", [0, 1, 2])
def test_every_complexity_and_ring_cost(complexity, cost):
    rings = ("RING_BLUE", "RING_ORANGE", "RING_GREEN")[:complexity]
    costs = {"RING_BLUE": cost, "RING_ORANGE": cost, "RING_GREEN": cost, "RING_YELLOW": 0}
    pl = ProductionPlanner(P16, "C")
    o = order(rings=rings, cap="CAP_GREY")
    net = pl.decompose(pl.context(world([o], costs), o))
    slide = steps(net, M.PUT_WORKPIECE, side=M.SLIDE)
    mounts = steps(net, M.MOUNT_RING)
    bs_gets = steps(net, M.GET_WORKPIECE, machine="C-BS")
    assert len(mounts) == complexity
    assert len(slide) == cost * complexity                      # every additional base
    reuse = cost > 0 and complexity > 0
    # the cap-less base serves as one additional base when any is needed, else discarded
    assert len(bs_gets) == 1 + cost * complexity - (1 if reuse else 0)
    assert len(steps(net, M.DISCARD)) == (0 if reuse else 1)
    assert len(steps(net, M.RETRIEVE_CAP, machine="C-CS1")) == 1
    [mount_cap] = steps(net, M.MOUNT_CAP, machine="C-CS1")
    [deliver] = steps(net, M.DELIVER)
    [retrieve] = steps(net, M.RETRIEVE_CAP)
    assert net.before(retrieve, mount_cap) and net.before(mount_cap, deliver)
    for i, m in enumerate(mounts):                               # rings in the order's order
        assert net.steps[m].fields["params"]["ring_color"] == rings[i]
        if i:
            assert net.before(mounts[i - 1], m)
        assert net.before(m, mount_cap)
        rs = net.steps[m].fields["params"]["machine"]
        feeds = [s for s in slide if net.steps[s].fields["params"]["machine"] == rs
                 and net.before(s, m)]
        assert len(feeds) >= cost                                # bases on the slide first
    # independent steps stay unordered: the first base and the cap retrieval
    first_get = min(bs_gets)
    assert not net.before(first_get, retrieve) and not net.before(retrieve, first_get)
    for s in slide:                                              # feeds parallel to the chain
        assert not net.before(first_get, s) or net.steps[s].fields["carry"]
    # carry steps always follow a pickup
    for i, st in enumerate(net.steps):
        if st.fields["carry"]:
            assert any(net.steps[j].fields["kind"] == M.GET_WORKPIECE
                       for j in net.predecessors(i))


def test_prepare_instructions_and_locks():
    pl = ProductionPlanner(P16, "C")
    o = order(rings=("RING_ORANGE",), cap="CAP_BLACK")
    net = pl.decompose(pl.context(world([o], {"RING_ORANGE": 1}), o))
    by_kind = {s.fields["kind"]: s.fields for s in net.steps}
    assert by_kind[M.MOUNT_RING]["prepare"] == {"machine": "C-RS2",
                                                "rs": {"ring_color": "RING_ORANGE"}}
    assert by_kind[M.RETRIEVE_CAP]["prepare"]["cs"] == {"operation": "RETRIEVE_CAP"}
    assert by_kind[M.MOUNT_CAP]["prepare"]["cs"] == {"operation": "MOUNT_CAP"}
    assert by_kind[M.DELIVER]["prepare"] == {"machine": "C-DS", "ds": {"gate": 1}}
    assert "C-CS2#cap" in by_kind[M.RETRIEVE_CAP]["locks"]
    pl25 = ProductionPlanner(rules.profile("rcll2025"), "C")
    net = pl25.decompose(pl25.context(world([o], {"RING_ORANGE": 1}), o))
    assert [s.fields["prepare"] for s in net.steps if s.fields["kind"] == M.DELIVER] == [
        {"machine": "C-DS", "ds": {"order_id": 1}}]


def test_repair_continues_from_the_workpiece_as_it_is():
    pl = ProductionPlanner(P16, "C")
    o = order(rings=("RING_BLUE", "RING_ORANGE"), cap="CAP_GREY")
    costs = {"RING_BLUE": 2, "RING_ORANGE": 1}
    w = world([o], costs)
    held = Progress(base="BASE_RED", rings=("RING_BLUE",), location="robot:2",
                    slide_credit={"C-RS2": 1}, cap_ready="C-CS1")
    net = pl.decompose(pl.context(w, o, held))
    assert steps(net, M.GET_WORKPIECE, machine="C-BS") == []     # nothing new from the BS
    assert steps(net, M.RETRIEVE_CAP) == [] and steps(net, M.PUT_WORKPIECE) == []
    [mount] = steps(net, M.MOUNT_RING)
    assert net.steps[mount].fields["holder"] == "2"              # the robot holding it
    at_output = Progress(base="BASE_RED", rings=("RING_BLUE",), location="C-RS1:OUTPUT")
    net = pl.decompose(pl.context(w, o, at_output))
    assert net.steps[0].fields["kind"] == M.GET_WORKPIECE
    assert net.steps[0].fields["params"]["machine"] == "C-RS1"
    wrong = Progress(base="BASE_BLACK", location="robot:1")
    with pytest.raises(PlanningFailed):
        pl.decompose(pl.context(w, o, wrong))


def test_no_station_for_a_colour_means_no_plan():
    pl = ProductionPlanner(P16, "C")
    o = order(rings=("RING_BLUE",))
    w = world([o], {"RING_BLUE": 0}, unusable=frozenset({"C-RS1"}))
    with pytest.raises(PlanningFailed):
        pl.decompose(pl.context(w, o))


def test_engine_backtracks_over_siblings_and_keeps_partial_order():
    d = Domain("t")
    d.operator("a")(lambda ctx, x: {"x": x})
    d.operator("b")(lambda ctx, x: {"x": x} if x == 2 else None)
    d.method("pick")(lambda ctx: iter([("a", 1), ("a", 2)]))
    d.method("top")(lambda ctx: Seq(Par(("pick",), ("a", 9)), ("needs",)))

    @d.method("needs")
    def m(ctx):
        return ("b", 2)

    net = Planner(d).plan(None, ("top",))
    assert [s.fields["x"] for s in net.steps] == [1, 9, 2]
    assert net.before(0, 2) and net.before(1, 2) and not net.before(0, 1)


def test_choose_prefers_what_scores_and_drops_what_is_over():
    pl = ProductionPlanner(P16, "C", clock=SimClock(), max_evaluations=200)
    costs = {"RING_BLUE": 2, "RING_GREEN": 0, "RING_ORANGE": 1, "RING_YELLOW": 0}
    orders = [order(1, (), "CAP_BLACK", end=900),
              order(2, ("RING_ORANGE",), "CAP_GREY", begin=0, end=500),
              order(3, ("RING_BLUE",), "CAP_GREY", begin=0, end=85)]
    w = world(orders, costs, max_products=1, now=100.0)
    assert {c.order.id for c in pl.candidates(w)} == {1, 2}     # 3 is over (end + grace)
    ch = pl.choose(w)
    assert [c.order.id for c in ch.start] == [2]                # a C1 is worth more than a C0
    assert ch.points > ch.baseline_points
    again = pl.choose(world(orders, costs, max_products=1, now=100.0))
    assert [c.order.id for c in again.start] == [2] and again.points == ch.points


def test_choose_respects_work_in_progress_and_budget():
    pl = ProductionPlanner(P16, "C", clock=SimClock(), max_evaluations=3)
    orders = [order(i) for i in range(1, 6)]
    ch = pl.choose(world(orders, {}, max_products=3))
    assert ch.evaluations <= 3
    full = pl.choose(world(orders, {}, max_products=2, in_progress={1: 1, 2: 1}))
    assert full.start == []                          # both slots taken


class _TickingClock:
    """A clock that moves on by ``step`` seconds each time it is read, so the
    planner's wall-time budget runs out after a known number of evaluations."""

    def __init__(self, step: float):
        self.t, self.step = 0.0, step

    def now(self) -> float:
        self.t += self.step
        return self.t


def test_choose_stops_when_its_time_budget_is_spent():
    orders = [order(i) for i in range(1, 9)]
    free = ProductionPlanner(P16, "C", clock=SimClock(), budget=0.04, max_evaluations=1000)
    unlimited = free.choose(world(orders, {}, max_products=3))
    timed = ProductionPlanner(P16, "C", clock=_TickingClock(0.01), budget=0.04, max_evaluations=1000)
    ch = timed.choose(world(orders, {}, max_products=3))
    assert unlimited.evaluations > 6                 # without the budget it looks further
    assert 1 <= ch.evaluations <= 5                  # 40 ms at 10 ms a look: the search stops
    assert ch.points >= ch.baseline_points           # and still returns the best found so far
