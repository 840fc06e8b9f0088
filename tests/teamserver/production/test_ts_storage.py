"""The 2025 storage station: a product finished long before its order's window opens
is stored there and retrieved shortly before the window, exactly when that pays;
never in the 2016 rules (no storage station)."""
import math

import pytest

from rll_bt import rules
from teamserver.knowledge import model as M
from teamserver.planning.domain import Progress
from teamserver.planning.estimate import SimRobot
from teamserver.planning.htn import PlanningFailed
from teamserver.planning.planner import ProductionPlanner, StoragePolicy, World
from tests.support.teamserver import C0, Lockstep, Stations, machines_known, play

P25, P16 = rules.profile("rcll2025"), rules.profile("rcll2016")
RS25 = {"C-RS1": ("RING_ORANGE", "RING_GREEN"), "C-RS2": ("RING_BLUE", "RING_YELLOW")}
CAPS = {"C-CS1": "CAP_GREY", "C-CS2": "CAP_BLACK"}
COSTS = {"RING_ORANGE": 1, "RING_GREEN": 0, "RING_BLUE": 2, "RING_YELLOW": 0}
ZONES25 = {"C-BS": 31, "C-DS": 13, "C-SS": 33, "C-RS1": 24, "C-RS2": 44, "C-CS1": 36,
           "C-CS2": 66}
POS25 = {m: P25.zone_centre(z) for m, z in ZONES25.items()}


def world(orders, *, now=0.0, positions=POS25, rs=RS25, **kw):
    return World(orders, [SimRobot(str(i), (4.5, 0.5), now) for i in (1, 2, 3)], positions,
                 rs, COSTS, CAPS, now=now, horizon=1200.0, **kw)


def order(oid=3, rings=(), begin=0, end=1200, cap="CAP_BLACK"):
    return M.Order(oid, len(rings), "BASE_RED", tuple(rings), cap, 1, 0, begin, end, 1)


def kinds(net, machine=None):
    return [(s.fields["kind"], s.fields["params"].get("machine")) for s in net.steps
            if machine is None or s.fields["params"].get("machine") == machine]


def index(net, kind, machine):
    [i] = [i for i, s in enumerate(net.steps) if s.fields["kind"] == kind
           and s.fields["params"].get("machine") == machine]
    return i


def threshold(pl, o, w):
    """(the product's estimated ready time, the wait from which storing pays)."""
    ctx = pl.context(w, o)
    return pl.ready_time(pl.htn.plan(ctx, ("product",)), o, w), ctx.storage.min_wait


def test_a_product_ready_long_before_its_window_is_stored_and_retrieved_for_it():
    pl = ProductionPlanner(P25, "C")
    o = order(rings=("RING_ORANGE",), begin=700, end=1000)
    w = world([o])
    net = pl.decompose(pl.context(w, o), w)
    assert kinds(net, "C-SS") == [(M.PUT_WORKPIECE, "C-SS"), (M.GET_WORKPIECE, "C-SS")]
    store, get = index(net, M.PUT_WORKPIECE, "C-SS"), index(net, M.GET_WORKPIECE, "C-SS")
    cap, deliver = index(net, M.MOUNT_CAP, "C-CS2"), index(net, M.DELIVER, "C-DS")
    assert net.before(cap, store) and net.before(store, get) and net.before(get, deliver)
    st, gt = net.steps[store].fields, net.steps[get].fields
    # STORE at the input from the robot that took the product off the cap station...
    assert st["carry"] and st["params"]["side"] == M.INPUT and st["locks"] == ("C-SS",)
    assert st["prepare"] == {"machine": "C-SS", "ss": {"operation": "STORE", "shelf": None,
                                                        "slot": None}}
    assert net.steps[net.predecessors(store)[0]].fields["params"]["machine"] == "C-CS2"
    # ... RETRIEVE to the output 45 s before the window opens, delivered in the window
    assert gt["prepare"]["ss"]["operation"] == "RETRIEVE" and gt["params"]["side"] == M.OUTPUT
    assert gt["params"]["not_before"] == 700 - 45 and not gt["carry"]
    assert net.steps[deliver].fields["carry"] and net.predecessors(deliver) == [get]
    assert net.steps[deliver].fields["params"]["not_before"] == 700


def test_storage_steps_exactly_when_the_wait_pays_for_the_detour():
    pl = ProductionPlanner(P25, "C")
    probe = order(rings=("RING_ORANGE",), begin=900)
    ready, min_wait = threshold(pl, probe, world([probe]))
    fee = 10 / StoragePolicy().point_value        # storing and retrieving cost 5 points each
    assert 60 < ready < 400 and 40 + fee < min_wait < 150 + fee
    assert min_wait == pytest.approx(pl.storage_cost(POS25) + 30.0 + fee)
    for begin, stored in [(0, False),                                  # standing order
                          (math.floor(ready), False),                   # ready as it opens
                          (math.floor(ready + min_wait) - 1, False),    # not quite worth it
                          (math.ceil(ready + min_wait) + 1, True),
                          (1000, True)]:
        o = order(rings=("RING_ORANGE",), begin=begin, end=begin + 200)
        w = world([o])
        net = pl.decompose(pl.context(w, o), w)
        assert bool(kinds(net, "C-SS")) is stored, begin
    # later in the game, with other work in progress, the same window may no longer pay
    o = order(rings=("RING_ORANGE",), begin=math.ceil(ready + min_wait) + 1)
    assert not kinds(pl.decompose(pl.context(world([o], now=100.0), o), world([o], now=100.0)),
                     "C-SS")


@pytest.mark.parametrize("why", ["2016", "disabled", "unusable", "no estimate"])
def test_no_storage_without_a_usable_storage_station(why):
    o = order(rings=("RING_ORANGE",), begin=900)
    w = world([o])
    pl = ProductionPlanner(P25, "C")
    if why == "2016":
        pos16 = {m: P16.zone_centre(z) for m, z in
                 {"C-BS": 9, "C-DS": 4, "C-RS1": 2, "C-RS2": 7, "C-CS1": 11, "C-CS2": 6}.items()}
        rs16 = {"C-RS1": ("RING_BLUE", "RING_GREEN"), "C-RS2": ("RING_ORANGE", "RING_YELLOW")}
        pl, w = ProductionPlanner(P16, "C"), world([o], positions=pos16, rs=rs16)
        assert pl.ss is None and pl.context(w, o).storage is None
    elif why == "disabled":
        pl = ProductionPlanner(P25, "C", storage=StoragePolicy(enabled=False))
    elif why == "unusable":
        w = world([o], unusable=frozenset({"C-SS"}))
    net = pl.decompose(pl.context(w, o), None if why == "no estimate" else w)
    assert not any(s.fields["params"].get("machine", "").endswith("SS") for s in net.steps)
    assert net.steps[-1].fields["kind"] == M.DELIVER


def test_a_finished_product_is_handed_over_from_where_it_is():
    pl = ProductionPlanner(P25, "C")
    o = order(rings=("RING_ORANGE",), begin=700)
    w = world([o], now=300.0)
    done = {"base": "BASE_RED", "rings": ("RING_ORANGE",), "cap": "CAP_BLACK"}
    # on the shelf: retrieved from its place and delivered
    net = pl.decompose(pl.context(w, o, Progress(location="C-SS:SHELF", stored_at=(2, 5),
                                                 **done)), w)
    assert kinds(net) == [(M.GET_WORKPIECE, "C-SS"), (M.DELIVER, "C-DS")]
    assert net.steps[0].fields["prepare"]["ss"] == {"operation": "RETRIEVE", "shelf": 2,
                                                     "slot": 5}
    # in a gripper, 400 s early: stored by that robot
    net = pl.decompose(pl.context(w, o, Progress(location="robot:2", **done)), w)
    assert kinds(net) == [(M.PUT_WORKPIECE, "C-SS"), (M.GET_WORKPIECE, "C-SS"),
                          (M.DELIVER, "C-DS")]
    assert net.steps[0].fields["holder"] == "2"
    # in a gripper, the window about to open: delivered by that robot
    soon = world([o], now=680.0)
    net = pl.decompose(pl.context(soon, o, Progress(location="robot:2", **done)), soon)
    assert kinds(net) == [(M.DELIVER, "C-DS")] and net.steps[0].fields["holder"] == "2"
    # on the cap station's output: taken, then stored
    net = pl.decompose(pl.context(w, o, Progress(location="C-CS2:OUTPUT", **done)), w)
    assert kinds(net)[:2] == [(M.GET_WORKPIECE, "C-CS2"), (M.PUT_WORKPIECE, "C-SS")]
    # a finished workpiece of another product is no use
    with pytest.raises(PlanningFailed):
        pl.decompose(pl.context(w, o, Progress(location="robot:2", base="BASE_RED",
                                               rings=("RING_ORANGE",), cap="CAP_GREY")), w)


# -- against scripted 2025 stations ------------------------------------------------------

class Stations2025(Stations):
    """The scripted stations as the 2025 refbox runs them: the DS prepared with an order
    id (it counts a product for that order inside its window), the SS storing what is
    fed for STORE and bringing a stored workpiece to its output for RETRIEVE."""

    def __init__(self, ls):
        super().__init__(ls)
        self.shelf: dict = {}               # (shelf, slot) -> product id stored there
        self.ss_ops: list = []              # (game time, operation, shelf, slot)
        self.storing: str | None = None     # product whose workpiece is on the SS input
        self.stock: dict = {}               # (shelf, slot) -> description of a C0 there

    def _send(self):
        rb = self.ls.refbox
        info = rb.ms.MachineInfo(team_color=0)
        e = rb.ms.enum("RingColor")
        for name, state in self.states.items():
            m = info.machines.add(name=name, state=state, type=name[2:4])
            for c in RS25.get(name, ()):
                m.ring_colors.append(e.Value(c))
            if name in self.slides:
                m.loaded_with = self.slides[name]
            if name == "C-SS":                 # status_ss: every place, filled or not
                for sh in range(6):
                    for sl in range(8):
                        place = m.status_ss.add(shelf=sh, slot=sl,
                                                is_filled=(sh, sl) in self.shelf)
                        if (sh, sl) in self.stock:
                            place.description = self.stock[(sh, sl)]
        rb.cyan.send(info)

    def take_prepares(self, gt):
        got = self.ls.refbox.received[self.seen:]
        ops = self.ls.refbox.ms.enum("SSOp")
        for m in got:
            if m.DESCRIPTOR.name == "PrepareMachine" and m.machine == "C-SS" and \
                    self.states["C-SS"] == "IDLE":
                i = m.instruction_ss
                self.ss_ops.append((gt, ops.Name(i.operation), i.shelf, i.slot))
        super().take_prepares(gt)
        instr = self.instr.get("C-SS")
        if self.states["C-SS"] == "PREPARED" and ops.Name(instr.instruction_ss.operation) == \
                "RETRIEVE":
            assert (instr.instruction_ss.shelf, instr.instruction_ss.slot) in self.shelf
            del self.shelf[(instr.instruction_ss.shelf, instr.instruction_ss.slot)]
            self.stock.pop((instr.instruction_ss.shelf, instr.instruction_ss.slot), None)
            self.states["C-SS"] = "READY-AT-OUTPUT"
            self._send()

    def fed(self, machine, gt, task_id=None):
        t = self.ls.server.kb.tasks.get(task_id)
        self.storing = t.product if t is not None and machine == "C-SS" else self.storing
        super().fed(machine, gt, task_id)

    def _process(self, machine, gt):
        if machine == "C-SS":
            i = self.instr[machine].instruction_ss
            assert (i.shelf, i.slot) not in self.shelf          # the refbox would break it
            self.shelf[(i.shelf, i.slot)] = self.storing
            self.states[machine] = "IDLE"
        elif machine == "C-DS":
            oid = self.instr[machine].instruction_ds.order_id
            self.deliveries.append((gt, oid))
            self.states[machine] = "IDLE"
            self._count(self.waiting_order.pop(machine, None), oid, gt)
        else:
            super()._process(machine, gt)

    def _count(self, order_id, prepared_for, gt):
        for o in self.ls.order_msgs:
            if o["id"] == order_id == prepared_for and \
                    o["delivery_period_begin"] <= gt <= o["delivery_period_end"]:
                o["quantity_delivered_cyan"] += 1
                self.ls.refbox.orders(self.ls.order_msgs)


T0 = 200.0          # production game time after the 180 s of exploration


def setup_2025(ls, stock=False):
    """Our colour, PRODUCTION running after exploration, known 2025 machines, ring costs,
    idle stations; the storage station's stock of C0 products (the rules' default
    storage) in it with ``stock``, else used up (claimed by nobody of ours)."""
    machines_known(ls, ZONES25, COSTS, T0)
    ls.stations = Stations2025(ls)
    if stock:
        for shelf, slot, base, cap in P25.prestored:
            ls.stations.shelf[(shelf, slot)] = "stock"
            ls.stations.stock[(shelf, slot)] = f"{base} {cap}"
    ls.stations._send()
    ls.step(n=2)


def send_orders(ls, orders):
    bc, cc = ls.refbox.ms.enum("BaseColor"), ls.refbox.ms.enum("CapColor")
    ls.order_msgs = [dict(C0, base_color=bc.Value("BASE_RED"), cap_color=cc.Value("CAP_BLACK"),
                          competitive=False, **o) for o in orders]
    ls.refbox.orders(ls.order_msgs)
    ls.step(n=2)


def estimate(ls, begin):
    """(ready, min_wait) the server's planner sees now for a C0 of order 3."""
    pm = ls.server.production
    o = order(3, begin=begin, end=begin + 300)
    w = pm.world.build(T0, 1200.0)
    return threshold(ls.server.planner, o, w)


def delivered(ls, oid):
    return lambda gt: any(p.state == "DELIVERED" and p.order_id == oid
                          for p in ls.server.kb.products.values()) and ls.stations.deliveries


def ss_prepares(ls):
    return [(m.instruction_ss.shelf, m.instruction_ss.slot) for m in ls.refbox.received
            if m.DESCRIPTOR.name == "PrepareMachine" and m.machine == "C-SS"]


def test_an_early_product_waits_in_the_storage_station_not_in_a_gripper():
    ls = Lockstep("rcll2025")
    setup_2025(ls)
    ready, min_wait = estimate(ls, 900)
    B = math.ceil(ready + min_wait) + 40                # storing pays (its points too)
    send_orders(ls, [{"id": 3, "delivery_period_begin": B, "delivery_period_end": B + 300}])
    kb, pm = ls.server.kb, ls.server.production
    [p] = [p for p in kb.products.values() if p.order_id == 3]
    assert any(t.params.get("store") for t in kb.tasks_of(p.tasks))    # planned so
    seen, shelf = [], []

    def waiting(gt):
        wp = kb.workpieces.get(p.workpiece or "")
        if wp is not None and wp.location == "C-SS:SHELF":
            seen.append((gt, [r.number for r in kb.robots.values() if r.holding == wp.id]))
            shelf.append((gt, dict(ls.stations.shelf), pm.shelf.places))
        return delivered(ls, 3)(gt)
    assert play(ls, waiting, t0=T0, steps=1200)
    # stored soon after it was made, still there until shortly before the window
    assert seen and seen[0][0] < T0 + 60 and seen[-1][0] > B - 45 - 5
    assert all(holding == [] for _, holding in seen)              # no robot holds it
    assert all(sh == {(0, 0): p.id} and ours == {"0,0": p.id}
               for gt, sh, ours in shelf if gt < B - 45)
    st = ls.stations
    assert [(op, sh, sl) for _, op, sh, sl in st.ss_ops] == [("STORE", 0, 0), ("RETRIEVE", 0, 0)]
    assert B - 45 <= st.ss_ops[1][0] < B                           # retrieved for the window
    [(gt, oid)] = st.deliveries
    assert oid == 3 and B <= gt <= B + 30                           # delivered as it opened
    assert ls.order_msgs[0]["quantity_delivered_cyan"] == 1
    assert p.repairs == 0 and pm.shelf.places == {} and st.shelf == {}


def test_a_product_whose_window_opens_soon_is_delivered_directly():
    ls = Lockstep("rcll2025")
    setup_2025(ls)
    send_orders(ls, [{"id": 3, "delivery_period_begin": 240, "delivery_period_end": 500}])
    assert play(ls, delivered(ls, 3), t0=T0, steps=400)
    assert ss_prepares(ls) == [] and ls.server.production.shelf.places == {}
    [(gt, oid)] = ls.stations.deliveries
    assert oid == 3 and gt >= 240


@pytest.mark.parametrize("actual", ["early", "late"])
def test_the_choice_is_made_again_when_the_product_is_finished(actual):
    """The plan's ready time is an estimate: quicker robots than it assumed finish a
    product early enough to store it after all; slower ones too late for storing."""
    ls = Lockstep("rcll2025")
    setup_2025(ls)
    ready, min_wait = estimate(ls, 900)
    # the plan hands it over directly (early) or stores it (late)
    begin = round(ready + min_wait + (-20 if actual == "early" else 20))
    send_orders(ls, [{"id": 3, "delivery_period_begin": begin, "delivery_period_end": begin + 300}])
    kb = ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 3]
    assert any(t.params.get("store") for t in kb.tasks_of(p.tasks)) is (actual == "late")
    # quick robots: every task takes 1.5 s; slow ones 60 s
    assert play(ls, delivered(ls, 3), t0=T0, steps=3000, drive=3 if actual == "early" else 120)
    stored = ss_prepares(ls)
    assert stored == ([(0, 0), (0, 0)] if actual == "early" else [])
    [(gt, oid)] = ls.stations.deliveries
    assert oid == 3 and begin <= gt <= begin + 300 and p.repairs == 0
    # the first plan's hand-over was replaced once the product was finished
    replaced = [(t.kind, t.machine) for t in kb.tasks_of(p.tasks) if t.state == M.CANCELLED]
    if actual == "early":
        assert replaced == [(M.DELIVER, "C-DS")]
    else:
        assert (M.PUT_WORKPIECE, "C-SS") in replaced and not any(
            t.machine == "C-SS" for t in kb.tasks_of(p.tasks) if t.state == M.DONE)


def test_a_product_brought_out_but_not_picked_up_is_taken_from_the_output():
    ls = Lockstep("rcll2025")
    setup_2025(ls)
    send_orders(ls, [{"id": 3, "delivery_period_begin": 400, "delivery_period_end": 700}])
    kb = ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 3]
    failed = []

    def fail(agent, t):
        if t.WhichOneof("kind") == "get_workpiece" and t.get_workpiece.machine == "C-SS" \
                and len(failed) < 3:
            failed.append(t.task_id)
            return {"error": "GRAB_FAILED", "holding": False}
        return None
    assert play(ls, delivered(ls, 3), t0=T0, steps=800, fail=fail)
    assert len(failed) == 3 and p.repairs == 1
    # one RETRIEVE only: after the repair the product was taken from the output
    assert [op for _, op, _, _ in ls.stations.ss_ops] == ["STORE", "RETRIEVE"]
    last = [t for t in kb.tasks_of(p.tasks) if t.machine == "C-SS" and t.state == M.DONE]
    assert [t.kind for t in last] == [M.PUT_WORKPIECE, M.GET_WORKPIECE]
    assert last[-1].prepare is None and ls.server.production.shelf.places == {}
    [(gt, oid)] = ls.stations.deliveries
    assert oid == 3 and 400 <= gt <= 700


def test_a_c0_is_delivered_from_the_stock_the_storage_station_began_with():
    """2025: six C0 products (every base x cap) are in the storage station at the start; a
    C0 order of one of them is a RETRIEVE (-5) and a delivery, not a product to make."""
    ls = Lockstep("rcll2025")
    setup_2025(ls, stock=True)
    send_orders(ls, [{"id": 3, "delivery_period_begin": int(T0) + 60,
                      "delivery_period_end": int(T0) + 360}])
    kb, pm = ls.server.kb, ls.server.production
    [p] = [p for p in kb.products.values() if p.order_id == 3]
    assert [t.kind for t in kb.tasks_of(p.tasks)] == [M.GET_WORKPIECE, M.DELIVER]
    assert pm.shelf.place_of(p.id) == (1, 1)            # BASE_RED + CAP_BLACK's place
    assert play(ls, delivered(ls, 3), t0=T0, steps=800)
    st = ls.stations
    assert [(op, sh, sl) for _, op, sh, sl in st.ss_ops] == [("RETRIEVE", 1, 1)]
    assert [oid for _, oid in st.deliveries] == [3]
    assert [(t.kind, t.state) for t in kb.tasks_of(p.tasks)] == [(M.GET_WORKPIECE, M.DONE),
                                                                 (M.DELIVER, M.DONE)]
    assert not [t for t in kb.tasks.values() if t.kind == M.MOUNT_CAP]     # nothing made
