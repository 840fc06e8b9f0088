"""Production against scripted stations: deliveries inside the order's window, lost
workpieces a station never took, stations left PREPARED with a stale instruction,
robots left holding what they cannot use yet, places the robots keep failing at."""
from teamserver.knowledge import model as M
from teamserver.production.caps import FREE
from teamserver.server import ServerConfig
from tests.support.teamserver import RS_2016, Lockstep, Stations, abandon_all_products, play, production_setup
from tests.teamserver.production.test_ts_storage import send_orders, setup_2025


def ds_gates(ls):
    return [m.instruction_ds.gate for m in ls.refbox.received
            if m.DESCRIPTOR.name == "PrepareMachine" and m.machine == "C-DS"]


def delivered(ls, *orders):
    """Until our products for ``orders`` are delivered and the DS processed as many."""
    kb = ls.server.kb
    return lambda gt: all(any(p.state == "DELIVERED" and p.order_id == o
                              for p in kb.products.values()) for o in orders) and len(
        ls.stations.deliveries) >= len(orders)


def test_a_delivery_waits_for_the_orders_window():
    ls = Lockstep()
    production_setup(ls, [{"id": 2, "delivery_period_begin": 70, "delivery_period_end": 300,
                               "delivery_gate": 2}])
    starts = {}

    def note(agent, t):
        if t.WhichOneof("kind") == "deliver":
            starts[t.task_id] = ls.server.refbox.game_time()
        return None
    assert play(ls, delivered(ls, 2), fail=note)
    [(gt, gate)] = ls.stations.deliveries
    assert gate == 2 and 70 <= gt <= 300                    # not "too soon"
    assert starts and all(t >= 70 - 60 for t in starts.values())   # nobody waits at the DS
    [p] = [p for p in ls.server.kb.products.values() if p.order_id == 2]
    done = {ls.server.kb.tasks[i].kind: ls.server.kb.tasks[i] for i in p.tasks}
    assert done[M.MOUNT_CAP].finished_at < 60                # built ahead of the window


def test_a_delivery_the_station_never_took_is_made_again_at_the_same_gate():
    ls = Lockstep()
    production_setup(ls, [{"id": 1, "delivery_gate": 3}])
    dropped = []

    def drop(agent, t):
        if t.WhichOneof("kind") == "deliver" and not dropped:
            dropped.append(t.task_id)
            return True
        return False
    assert play(ls, lambda gt: ls.stations.deliveries, drop=drop)
    kb = ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 1]
    assert kb.tasks[dropped[0]].state == M.FAILED and p.repairs == 1
    assert p.state == "DELIVERED"
    assert [g for _, g in ls.stations.deliveries] == [3]
    # the DS still waited with gate 3: the second delivery adopted that, no new prepare
    assert ds_gates(ls) == [3]


def test_a_feed_reported_failed_that_reached_the_station_counts_as_done():
    ls = Lockstep()
    production_setup(ls, [{"id": 1}])
    failed = []

    def fail(agent, t):
        if t.WhichOneof("kind") == "mount_cap" and not failed:
            failed.append(t.task_id)                 # it timed out backing off
            return {"error": "TIMEOUT", "holding": False, "fed": True}
        return None
    assert play(ls, delivered(ls, 1), fail=fail)
    kb = ls.server.kb
    [p] = [p for p in kb.products.values() if p.order_id == 1]
    assert kb.tasks[failed[0]].state == M.DONE and p.repairs == 0
    assert len([t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_CAP]) == 1
    assert [g for _, g in ls.stations.deliveries] == [1]


def test_a_feed_still_being_checked_is_neither_adopted_nor_flushed():
    ls = Lockstep()
    production_setup(ls, [{"id": 1, "delivery_gate": 1}])
    kb, feeds = ls.server.kb, ls.server.dispatcher.feeds
    t = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 1}, state=M.DONE,
               prepare={"machine": "C-DS", "ds": {"gate": 1}}, prepared_at=ls.clock.now())
    kb.save_task(t)
    feeds.sent(t)
    ls.station_states["C-DS"] = "PREPARED"
    ls.refbox.machines(ls.station_states)
    ls.step()
    feeds.finished(t)                        # done, the DS has not reported it yet
    again = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 1},
                   prepare={"machine": "C-DS", "ds": {"gate": 1}})
    assert feeds.instruction("C-DS") is None and not feeds.accepts(again)
    ls.station_states["C-DS"] = "IDLE"       # it processed the workpiece after all
    ls.refbox.machines(ls.station_states)
    ls.step()
    assert feeds.verify() == [] and kb.get("feeds") == {}


def test_one_robot_stays_free_while_the_others_hold_products_for_later_windows():
    ls = Lockstep()
    late = {"delivery_period_begin": 200, "delivery_period_end": 500}
    production_setup(ls, [dict(id=2, **late), dict(id=3, delivery_gate=2, **late),
                          dict(id=4, delivery_gate=3, **late)])
    kb = ls.server.kb
    most = []

    def waiting(gt):
        """Robots holding a product whose delivery is not ready."""
        deliver = {t.holder for t in kb.open_tasks() if t.kind == M.DELIVER
                   and t.holder is not None}
        most.append(sum(1 for r in kb.robots.values() if r.holding and r.number in deliver))
        return False
    play(ls, waiting, steps=260)                       # up to production time 130
    assert max(most) == 2 and most[-1] == 2
    # (the free robot may meanwhile retrieve caps ahead: products of no order)
    [third] = [p for p in kb.products.values() if p.order_id != 0 and not any(
        t.kind == M.DELIVER and t.holder is not None for t in kb.tasks_of(p.tasks))]
    [pickup] = [t for t in kb.tasks_of(third.tasks) if t.state == M.PENDING
                and t.kind == M.GET_WORKPIECE]
    assert pickup.machine[2:4] == "CS"                 # the third waits at the CS output
    assert ls.server.dispatcher.holding.stuck(130.0) == 2
    assert play(ls, delivered(ls, 2, 3, 4), t0=130, steps=300, dt=1.0)
    assert all(gt >= 200 for gt, _ in ls.stations.deliveries)


def test_a_slide_the_robots_keep_failing_at_is_planned_around():
    ls = Lockstep()
    # ORANGE costs one base on C-RS2's slide; the robots never manage to put anything
    # there: neither that base nor a workpiece discarded onto the slide
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_ORANGE"]}, {"id": 1}])
    kb = ls.server.kb
    tries = []

    def fail(agent, t):
        kind = t.WhichOneof("kind")
        if kind in ("put_workpiece", "discard") and getattr(t, kind).machine == "C-RS2":
            tries.append(t.task_id)
            return {"error": "NAVIGATION_FAILED", "holding": True}
        return None
    assert play(ls, delivered(ls, 1), fail=fail)
    play(ls, lambda gt: False, fail=fail, steps=100, t0=ls.server.refbox.game_time())
    assert len(set(tries)) == 4                              # then the slide is left alone
    assert "C-RS2:SLIDE" in ls.server.production.world.unusable()
    [c1] = [p for p in kb.products.values() if p.order_id == 5]
    assert c1.state == "ABANDONED"
    # what is discarded meanwhile goes onto the other ring station's slide
    assert [t.machine for t in kb.tasks.values() if t.kind == M.DISCARD and t.state == M.DONE] \
        == ["C-RS1", "C-RS1"]


def test_a_base_that_missed_the_slide_is_fetched_again_before_the_mount():
    ls = Lockstep()
    # ORANGE costs one base on C-RS2's slide; the first one falls beside it
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_ORANGE"]}])
    kb = ls.server.kb
    dropped, broke = [], []

    def drop(agent, t):
        if t.WhichOneof("kind") == "put_workpiece" and not dropped:
            dropped.append(t.task_id)
            return True
        return False

    def until(gt):
        if ls.stations.states["C-RS2"] == "BROKEN":
            broke.append(gt)
        return delivered(ls, 5)(gt)
    assert play(ls, until, drop=drop)
    assert not broke                                    # never mounted without the base
    [p] = [p for p in kb.products.values() if p.order_id == 5]
    puts = [t for t in kb.tasks_of(p.tasks) if t.kind == M.PUT_WORKPIECE]
    assert len(puts) == 2 and all(t.state == M.DONE for t in puts) and p.repairs == 0
    [mount] = [t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_RING]
    assert {t.id for t in puts} <= set(mount.deps)


def test_a_full_slide_takes_no_more_bases_until_a_mount_uses_some():
    ls = Lockstep()
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}])   # 2 bases, RS1
    pm, kb = ls.server.production, ls.server.kb
    ls.refbox.machines(ls.station_states, {"C-RS1": ("RING_BLUE", "RING_GREEN")},
                       **{"C-RS1": {"loaded_with": 3}})
    ls.step()
    [p] = [p for p in kb.products.values() if p.order_id == 5]
    put = next(t for t in kb.tasks_of(p.tasks) if t.kind == M.PUT_WORKPIECE)
    mount = next(t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_RING)
    assert not pm.slides.slide_ready(put) and pm.slides.slide_ready(mount)
    ls.refbox.machines(ls.station_states, {"C-RS1": ("RING_BLUE", "RING_GREEN")},
                       **{"C-RS1": {"loaded_with": 1}})
    ls.step()
    assert pm.slides.slide_ready(put) and not pm.slides.slide_ready(mount)


def test_a_mount_whose_full_slide_holds_its_cost_does_not_wait_for_its_own_bases():
    """Bases other products discarded fill the slide (3, the most it holds) before the
    products' own bases are put: a mount goes with the bases there, its own bases go
    on the slide after it, and the next mount gets them without fetching more
    (rcll2016 seeds 9 and 10, rcll2025 seed 10: the mount waited for puts that waited
    for room, and the robots held its workpiece and bases for the rest of the game)."""
    ls = Lockstep()
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]},    # 2 bases, RS1
                          {"id": 6, "complexity": 1, "rings": ["RING_BLUE"], "delivery_gate": 2}])
    ls.stations = Stations(ls)
    ls.stations.slides["C-RS1"] = 3
    ls.stations._send()
    kb, bad = ls.server.kb, []

    def until(gt):
        if ls.stations.states["C-RS1"] == "BROKEN" or ls.stations.slides["C-RS1"] > 3:
            bad.append(gt)
        return delivered(ls, 5, 6)(gt)
    assert play(ls, until, steps=1600)
    assert not bad
    products = [p for p in kb.products.values() if p.order_id in (5, 6)]
    mounts = [t for p in products for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_RING]
    puts = [t for p in products for t in kb.tasks_of(p.tasks) if t.kind == M.PUT_WORKPIECE]
    assert len(mounts) == 2 and len(puts) == 4                  # no base fetched beyond the plan
    first = min(mounts, key=lambda t: t.finished_at)
    waived = [t for t in puts if t.product == first.product and t.id not in first.deps]
    assert waived and all(t.assigned_at >= first.finished_at for t in waived if t.assigned_at)
    for p in products:          # a cap mount only once its cap is in the station (one of
        tasks = kb.tasks_of(p.tasks)                  # the bases is the cap retrieval's)
        [retrieve] = [t for t in tasks if t.kind == M.RETRIEVE_CAP and t.state == M.DONE]
        [mount_cap] = [t for t in tasks if t.kind == M.MOUNT_CAP and t.state == M.DONE]
        assert mount_cap.assigned_at >= retrieve.finished_at


def test_a_mount_waived_off_its_cap_less_base_still_lets_its_product_take_a_free_cap():
    """A ring mount whose full slide holds its cost no longer waits for the put of the
    cap-less base, only for its pickup (the cap must be in its station before the cap
    mount). A cap left free in that cap station (retrieved ahead, or by an abandoned
    product) is then this product's to mount: its retrieval could never go while the
    station holds a cap (rcll2016 seed 12 at 3b1cd15: the free cap was not offered to
    order 7's C3, whose robot held it with two rings from 479.6 s to the end, because
    its cap chain had two steps after the pickup, the put and the waived mount)."""
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}],   # 2 bases, RS1
                     states={"C-CS2": "DOWN"})
    ls.refbox.machines(ls.station_states, RS_2016, **{"C-RS1": {"loaded_with": 3}})
    pm, kb = ls.server.production, ls.server.kb
    ls.step(n=3)
    [p] = [p for p in kb.products.values() if p.order_id == 5]
    [pickup] = [t for t in kb.tasks_of(p.tasks) if t.params.get("role") == "capless"]
    [mount] = [t for t in kb.tasks_of(p.tasks) if t.kind == M.MOUNT_RING]
    assert pickup.id in mount.deps                          # waived: the slide is full
    pm.buffers.take("C-CS2", FREE)                          # a cap the station holds for nobody
    ls.step(n=3)
    tasks = kb.tasks_of(p.tasks)
    mount, pickup = kb.tasks[mount.id], kb.tasks[pickup.id]
    assert pm.buffers.owners["C-CS2"] == p.id               # it mounts the free cap
    assert pickup.state == M.CANCELLED and pickup.id not in mount.deps
    assert all(kb.tasks[d].state != M.CANCELLED for t in tasks if t.state == M.PENDING
               for d in t.deps)                             # nothing waits for a cancelled step
    ls.close()


def test_a_cap_retrieved_ahead_that_the_station_never_took_blocks_nothing():
    """A clean-up product (a cap retrieved ahead into an idle cap station) whose
    carrier never reached the station: what it booked is undone (no cap in the
    station for anyone to mount), its open tasks are cancelled and its locks freed,
    and the order is still made (it used to wait for that station for good)."""
    ls = Lockstep()
    production_setup(ls, [{"id": 1}])
    kb = ls.server.kb
    dropped = []

    def drop(agent, t):
        task = kb.tasks[t.task_id]
        p = kb.products.get(task.product or "")
        if t.WhichOneof("kind") == "retrieve_cap" and p is not None and p.order_id == 0 \
                and not dropped:
            dropped.append((task.id, p.id, task.machine))
            return True
        return False
    def fail(agent, t):                  # nothing comes out of the station: nothing to grab
        if t.WhichOneof("kind") == "get_workpiece" and dropped \
                and kb.tasks[t.task_id].product == dropped[0][1]:
            return {"error": "GRAB_FAILED", "holding": False}
        return None
    made = delivered(ls, 1)

    def settled(gt):
        return made(gt) and dropped and kb.products[dropped[0][1]].state != "ACTIVE" \
            and not kb.get("feeds")              # every feed checked
    assert play(ls, settled, drop=drop, fail=fail)
    [(task_id, cleanup, cs)] = dropped
    assert kb.tasks[task_id].state == M.FAILED
    x = kb.products[cleanup]
    assert x.state == "ABANDONED"
    assert not [t for t in kb.tasks_of(x.tasks) if t.state in M.OPEN_STATES]
    assert cleanup not in ls.server.production.locks.owners.values()
    assert cs not in ls.server.production.buffers.owners          # no cap there to mount
    assert [g for _, g in ls.stations.deliveries] == [1]


def test_2025_a_station_waiting_with_an_instruction_nothing_needs_is_fed_no_spare_base():
    """2025 breaks a machine left PREPARED for 20 s: it is IDLE again (after its 30 s
    BROKEN) long before a spare base from the BS could reach it, and that base would
    then lie on the input of an IDLE station for the next prepare to process."""
    ls = Lockstep("rcll2025", config=ServerConfig(prefill_caps=False))
    setup_2025(ls)
    send_orders(ls, [{"id": 1}, {"id": 2}])
    srv = ls.server
    kb, feeds = srv.kb, srv.dispatcher.feeds
    abandon_all_products(srv)
    # the DS waits for a delivery of order 1 that is over; order 2's needs another id
    old = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "order_id": 1},
                 state=M.DONE, prepare={"machine": "C-DS", "ds": {"order_id": 1}})
    kb.save_task(old)
    feeds.sent(old)
    ls.stations.states["C-DS"] = "PREPARED"
    ls.stations._send()
    ls.step()
    want2 = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "order_id": 2},
                   prepare={"machine": "C-DS", "ds": {"order_id": 2}}, carry=True, holder=1)
    kb.save_task(want2)
    assert feeds.instruction("C-DS") == {"machine": "C-DS", "ds": {"order_id": 1}}
    assert not feeds.accepts(want2)
    assert feeds.unstick() == []
    assert not [p for p in kb.products.values() if p.state == "ACTIVE"]


def test_two_robots_holding_bases_for_a_slide_with_room_for_one_send_only_one():
    """2025 seed 9: two robots holding bases were sent to C-RS1's slide in the same
    dispatch round while it held 2 (room for 1: both saw the room before either was
    assigned); the fourth base broke the station."""
    ls = Lockstep()
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}])
    srv, kb = ls.server, ls.server.kb
    ls.step(n=3)
    abandon_all_products(srv)
    ls.refbox.machines(ls.station_states, {"C-RS1": ("RING_BLUE", "RING_GREEN")}, **{"C-RS1": {"loaded_with": 2}})
    ls.step(n=3)
    puts = [M.Task(kb.next_id("task"), M.PUT_WORKPIECE, {"machine": "C-RS1", "side": M.SLIDE},
                   carry=True, holder=n) for n in (1, 2)]
    for t in puts:
        kb.save_task(t)
    ls.step(n=3)
    states = [kb.tasks[t.id].state for t in puts]
    assert states.count(M.ASSIGNED) == 1 and states.count(M.PENDING) == 1, states


def test_a_pickup_clearing_the_output_a_stuck_robot_waits_for_goes_while_two_robots_hold():
    """rcll2025 seed 18: robot 3 held P5 for its ring at C-RS1, whose output held P2 (C-RS1
    locked by P2); robot 2 held a base for C-RS1's full slide.  Fetching P2 leaves robot 1
    holding it (its next ring waits for bases): with two of three robots stuck that pickup
    was held back, robot 1 fetched a base for the full slide instead, and all three held
    their workpieces for the rest of the game (from 380 s)."""
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    production_setup(ls, [])
    kb, pm = ls.server.kb, ls.server.production
    ls.station_states["C-RS1"] = "READY-AT-OUTPUT"
    ls.refbox.machines(ls.station_states, RS_2016, **{"C-RS1": {"loaded_with": 3}})
    ls.step(n=3)
    ring = {"machine": "C-RS1", "ring_color": "RING_BLUE", "cost": 2}
    base = {"machine": "C-BS", "side": M.OUTPUT, "base": "BASE_RED", "role": "extra"}
    p5, p2, p6 = (pm.products.new("P", o) for o in (3, 2, 5))

    def task(product, kind, params, **kw):
        t = M.Task(kb.next_id("task"), kind, params, product=product.id, **kw)
        kb.save_task(t)
        product.tasks += (t.id,)
        kb.save_product(product)
        return t
    prep = {"machine": "C-RS1", "rs": {"ring_color": "RING_BLUE"}}
    mount5 = task(p5, M.MOUNT_RING, ring, carry=True, holder=3, locks=("C-RS1",), prepare=prep)
    get2 = task(p2, M.GET_WORKPIECE, {"machine": "C-RS1", "side": M.OUTPUT, "role": "main"},
                locks=("C-RS1",), releases=("C-RS1",))
    slide = {"machine": "C-RS1", "side": M.SLIDE}
    extras = [task(p, M.GET_WORKPIECE, base, locks=("C-BS",), releases=("C-BS",)) for p in (p2, p6)]
    put2, _ = (task(p, M.PUT_WORKPIECE, dict(slide, carry_from=e.id), carry=True, deps=(e.id,))
               for p, e in zip((p2, p6), extras))
    task(p2, M.MOUNT_RING, dict(ring, carry_from=get2.id), carry=True, deps=(get2.id, put2.id),
         locks=("C-RS1",), prepare=prep)
    put6 = task(p6, M.PUT_WORKPIECE, slide, carry=True, holder=2)
    pm.locks.grant({"C-RS1": p2.id})
    for n, wp in ((3, "P5/wp"), (2, "P6/base")):
        r = kb.robots[n]
        r.holding = wp
        kb.save_robot(r)
    ls.step(n=3)
    assert kb.tasks[get2.id].state == M.ASSIGNED and kb.tasks[get2.id].robot == 1
    ls.agents[0].result(get2.id, holding=True)
    ls.station_states["C-RS1"] = "IDLE"
    ls.refbox.machines(ls.station_states, RS_2016, **{"C-RS1": {"loaded_with": 3}})
    ls.step(n=3)
    assert kb.tasks[mount5.id].state == M.ASSIGNED and kb.tasks[mount5.id].robot == 3
    assert kb.tasks[put6.id].state == M.PENDING


def test_when_every_robot_is_stuck_a_base_for_a_full_slide_goes_to_another_slide():
    """rcll2025 seed 18 (after the swap above): from 480 s robot 3 held a base for C-RS1's
    full slide while robots 1 and 2 held products whose next steps waited for work
    nobody was free to do; the base now goes to C-RS2's slide (room for 2) and robot 3
    does that work."""
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    production_setup(ls, [])
    kb, pm = ls.server.kb, ls.server.production
    ls.refbox.machines(ls.station_states, RS_2016, **{"C-RS1": {"loaded_with": 3},
                                                      "C-RS2": {"loaded_with": 1}})
    ls.step(n=3)
    pa, pb = pm.products.new("P", 2), pm.products.new("P", 3)
    get = M.Task(kb.next_id("task"), M.GET_WORKPIECE, {"machine": "C-BS", "side": M.OUTPUT,
                                                        "base": "BASE_RED", "role": "extra"},
                 product=pa.id, locks=("C-BS",), releases=("C-BS",))
    mounts = [M.Task(kb.next_id("task"), M.MOUNT_RING, {"machine": "C-RS2", "cost": 0,
                                                        "ring_color": "RING_YELLOW"},
                     product=pa.id, carry=True, holder=n, deps=(get.id,), locks=("C-RS2",))
              for n in (1, 2)]
    put = M.Task(kb.next_id("task"), M.PUT_WORKPIECE, {"machine": "C-RS1", "side": M.SLIDE},
                 product=pb.id, carry=True, holder=3)
    for t in [get, put, *mounts]:
        kb.save_task(t)
    pa.tasks, pb.tasks = (get.id, *(m.id for m in mounts)), (put.id,)
    kb.save_product(pa)
    kb.save_product(pb)
    for n in (1, 2, 3):
        r = kb.robots[n]
        r.holding = f"wp{n}"
        kb.save_robot(r)
    ls.step(n=3)
    assert kb.tasks[put.id].kind == M.PUT_WORKPIECE          # not at once: all may be stuck a moment
    for _ in range(20):
        for a in ls.agents:
            a.status(holding=True)
        ls.step(dt=0.5)
    put = kb.tasks[put.id]
    assert (put.kind, put.params["machine"], put.state, put.robot) == (M.DISCARD, "C-RS2", M.ASSIGNED, 3)
    ls.agents[2].result(put.id)
    ls.step(n=3)
    assert kb.tasks[get.id].state == M.ASSIGNED and kb.tasks[get.id].robot == 3


def test_a_mount_whose_slide_holds_its_cost_goes_without_waiting_for_its_own_bases():
    """A ring mount whose workpiece is ready and whose slide holds what the ring costs
    (bases other products discarded there) goes at once: its own bases go on the slide
    after it, and the cap-less base's pickup, so the cap retrieval, is what the cap
    mount waits for (rcll2016 seeds 9 and 12: a C2's and a C3's robot held them at the
    ring station for 140 s and 347 s beside the bases while their caps waited for a
    cap station busy with another product's cap)."""
    ls = Lockstep()
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}],   # 2 bases, RS1
                     states={"C-CS2": "DOWN"})                 # no cap retrieved for now
    ls.stations = Stations(ls)
    ls.stations.slides["C-RS1"] = 2
    ls.stations._send()
    kb, bad = ls.server.kb, []
    [p] = [p for p in kb.products.values() if p.order_id == 5]

    def mounted(gt):
        if "BROKEN" in ls.stations.states.values() or ls.stations.slides["C-RS1"] > 3:
            bad.append(gt)
        return any(t.kind == M.MOUNT_RING and t.state == M.DONE for t in kb.tasks_of(p.tasks))
    assert play(ls, mounted, steps=400)                     # while C-CS2 is still DOWN
    tasks = kb.tasks_of(p.tasks)
    [retrieve] = [t for t in tasks if t.kind == M.RETRIEVE_CAP]
    [pickup] = [t for t in tasks if t.params.get("role") == "capless"]
    [mount_cap] = [t for t in tasks if t.kind == M.MOUNT_CAP]
    assert retrieve.state == M.PENDING and pickup.id in mount_cap.deps
    ls.stations.states["C-CS2"] = "IDLE"
    ls.stations._send()

    def done(gt):
        if "BROKEN" in ls.stations.states.values() or ls.stations.slides["C-RS1"] > 3:
            bad.append(gt)
        return delivered(ls, 5)(gt)
    assert play(ls, done, t0=300.0, steps=1200)
    assert not bad
    retrieve, mount_cap = kb.tasks[retrieve.id], kb.tasks[mount_cap.id]
    assert mount_cap.assigned_at >= retrieve.finished_at
    ls.close()
