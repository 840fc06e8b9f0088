"""The dispatcher with scripted robots over loopback TCP (and the in-process bus):
assignment by travel cost, station locks, PrepareMachine timing, failures and repair."""
import pytest

from teamserver.dispatch.config import DispatchConfig
from teamserver.knowledge import model as M
from teamserver.links.agents import from_wire, wire_id
from teamserver.server import ServerConfig
from tests.support.teamserver import RS_2016, Lockstep, production_setup, run_tasks, task_kinds

#: these tests look at the dispatch of one product's steps: no caps retrieved ahead
ALONE = ServerConfig(prefill_caps=False)


@pytest.fixture
def tcp():
    ls = Lockstep(tcp=True, config=ALONE)
    yield ls
    ls.close()


def place(ls, poses):
    for a, pose in zip(ls.agents, poses):
        a.pose = pose
        a.status()


def prepares(ls):
    return [m for m in ls.refbox.received if m.DESCRIPTOR.name == "PrepareMachine"]


def test_tasks_go_to_the_nearest_idle_robot_over_tcp(tcp):
    ls = tcp
    place(ls, [(0.5, 5.5, 0.0), (5.0, 1.6, 0.0), (3.0, 3.2, 0.0)])
    production_setup(ls, [{"id": 1}])
    ls.step(n=5)
    by_robot = {a.number: task_kinds(a) for a in ls.agents}
    assert by_robot[2] == [(by_robot[2][0][0], "get_workpiece", "C-BS")]     # next to the BS
    assert [k[1:] for k in by_robot[3]] == [("retrieve_cap", "C-CS2")]       # next to CS2
    assert by_robot[1] == []
    t = ls.agents[2].tasks()[0]
    assert t.retrieve_cap.shelf_slot == 0 and t.team_color == 0 and t.robot_id == 3


def test_prepare_machine_waits_until_the_robot_is_about_to_arrive(tcp):
    ls = tcp
    ls.server.config.dispatch.prepare_retry = 3.0
    place(ls, [(0.5, 5.5, 0.0), (1.0, 5.0, 0.0), (0.2, 5.8, 0.0)])
    production_setup(ls, [{"id": 1}])
    ls.step(n=5)
    got_bs = [a for a in ls.agents if any(k[2] == "C-BS" for k in task_kinds(a))]
    assert len(got_bs) == 1
    assert not [p for p in prepares(ls) if p.machine == "C-BS"]               # still far away
    robot = got_bs[0]
    robot.pose = (5.0, 1.2, 0.0)                                              # 0.45 m away
    robot.status()
    ls.step(n=3)
    pm = [p for p in prepares(ls) if p.machine == "C-BS"]
    assert len(pm) == 1
    assert pm[0].instruction_bs.color == ls.refbox.ms.enum("BaseColor").Value("BASE_RED")
    assert pm[0].instruction_bs.side == 2 and pm[0].team_color == 0
    ls.step(dt=1.0, n=4)                                    # the station never reacted: resend
    assert len([p for p in prepares(ls) if p.machine == "C-BS"]) == 2
    ls.station_states["C-BS"] = "PREPARED"
    ls.refbox.machines(ls.station_states)
    ls.step(dt=1.0, n=6)
    assert len([p for p in prepares(ls) if p.machine == "C-BS"]) == 2         # it reacted


def test_one_robot_at_a_station_at_a_time():
    # four robots: one may hold its base until the cap is ready, and two stay free
    ls = Lockstep(robots=4)
    place(ls, [(5.0, 1.6, 0.0), (4.8, 1.7, 0.0), (5.2, 1.7, 0.0), (4.6, 1.6, 0.0)])
    production_setup(ls, [{"id": 1}, {"id": 2, "delivery_gate": 2}])
    ls.step(n=5)
    bs = [(a, k) for a in ls.agents for k in task_kinds(a) if k[2] == "C-BS"]
    assert len(bs) == 1                                      # two products, one BS
    agent, (tid, _, _) = bs[0]
    agent.result(tid, holding=True)
    ls.step(n=5)
    bs = [(a, k) for a in ls.agents for k in task_kinds(a) if k[2] == "C-BS"]
    assert len(bs) == 2                                      # the next one once it is free


def test_a_lost_workpiece_is_repaired_and_the_product_still_delivered():
    ls = Lockstep()
    production_setup(ls, [{"id": 1}])
    kb = ls.server.kb
    failed = []

    def fail(agent, t):
        if t.WhichOneof("kind") == "mount_cap" and not failed:
            failed.append(t.task_id)
            return {"error": "PUT_FAILED", "holding": False}
        return None

    def delivered():
        return any(p.state == "DELIVERED" and p.order_id == 1
                                for p in kb.products.values())
    assert run_tasks(ls, delivered, fail)
    [p] = [p for p in kb.products.values() if p.order_id == 1]
    assert p.repairs == 1
    states = [kb.tasks[i].state for i in p.tasks]
    assert kb.tasks[failed[0]].state == M.FAILED
    assert M.CANCELLED in states or states.count(M.DONE) > 7     # re-planned from a new base
    gets = [kb.tasks[i] for i in p.tasks if kb.tasks[i].kind == M.GET_WORKPIECE
            and kb.tasks[i].machine == "C-BS" and kb.tasks[i].state == M.DONE]
    assert len(gets) == 2
    # the cap buffered before the failure was mounted after it: one retrieval only
    assert sum(1 for i in p.tasks if kb.tasks[i].kind == M.RETRIEVE_CAP
               and kb.tasks[i].state == M.DONE) == 1


def test_a_retryable_failure_tries_the_same_step_again():
    ls = Lockstep(config=ALONE)
    production_setup(ls, [{"id": 1}])
    kb = ls.server.kb
    failed = []

    def fail(agent, t):
        if t.WhichOneof("kind") == "deliver" and not failed:
            failed.append((agent.number, t.task_id))
            return {"error": "NAVIGATION_FAILED", "holding": True}
        return None

    assert run_tasks(ls, lambda: any(p.state == "DELIVERED" for p in kb.products.values()),
                     fail)
    number, tid = failed[0]
    assert kb.tasks[tid].state == M.FAILED
    [again] = [t for t in kb.tasks.values() if t.kind == M.DELIVER and t.id != tid]
    assert again.state == M.DONE and again.attempts == 2 and again.robot == number
    assert again.id > tid                     # a new id: agents remember finished task ids
    assert all(p.repairs == 0 for p in kb.products.values())


def test_a_broken_station_with_our_workpiece_inside_triggers_repair():
    ls = Lockstep()
    production_setup(ls, [{"id": 1, "complexity": 1, "rings": ["RING_GREEN"]}])
    kb = ls.server.kb
    def mounted():
        return any(t.kind == M.MOUNT_RING and t.state == M.DONE
                              for t in kb.tasks.values())
    assert run_tasks(ls, mounted)
    ls.station_states["C-RS1"] = "BROKEN"
    ls.refbox.machines(ls.station_states)
    ls.step(n=2)
    [p] = [p for p in kb.products.values() if p.order_id == 1]
    assert p.repairs == 1
    open_kinds = [(kb.tasks[i].kind, kb.tasks[i].machine) for i in p.tasks
                  if kb.tasks[i].state in M.OPEN_STATES]
    assert (M.GET_WORKPIECE, "C-BS") in open_kinds            # start again from a base
    assert not any(m == "C-RS1" and kb.tasks[i].state == M.ASSIGNED
                   for i in p.tasks for k, m in [(kb.tasks[i].kind, kb.tasks[i].machine)])
    ls.station_states["C-RS1"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    assert run_tasks(ls, lambda: p.state == "DELIVERED" or kb.products[p.id].state ==
                     "DELIVERED")


def test_new_order_is_planned_at_once():
    ls = Lockstep()
    production_setup(ls, [])
    assert not ls.server.kb.products
    ls.refbox.orders([{"id": 5, "complexity": 0, "base_color": 1, "cap_color": 2, "quantity_requested": 1,
                           "quantity_delivered_cyan": 0, "quantity_delivered_magenta": 0,
                           "delivery_period_begin": 0, "delivery_period_end": 900, "delivery_gate": 3}])
    ls.step(n=2)
    assert [p.order_id for p in ls.server.kb.products.values() if p.order_id] == [5]


def bs_task_after_setup(ls, poses):
    """Robots placed at ``poses``, one order: (the knowledge base, the
    assigned base-station task)."""
    place(ls, poses)
    production_setup(ls, [{"id": 1}])
    ls.step(n=5)
    kb = ls.server.kb
    [bs] = [t for t in kb.tasks.values() if t.machine == "C-BS" and t.state == M.ASSIGNED]
    return kb, bs


def test_a_station_going_down_before_its_prepare_frees_the_robot_sent_there(tcp):
    ls = tcp
    kb, bs = bs_task_after_setup(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0)])  # far from the BS
    agent = next(a for a in ls.agents if a.number == bs.robot)
    assert bs.prepared_at is None                                  # still on its way
    ls.station_states["C-BS"] = "DOWN"
    ls.refbox.machines(ls.station_states)
    ls.step(n=3)
    assert kb.tasks[bs.id].state == M.PENDING and kb.tasks[bs.id].robot is None
    assert kb.robots[agent.number].task_id != bs.id
    assert [c.task_id for c in agent.cancels()] == [bs.id]          # the robot was told to stop
    assert not [p for p in prepares(ls) if p.machine == "C-BS"]
    ls.station_states["C-BS"] = "IDLE"                             # back up: work goes on
    ls.refbox.machines(ls.station_states)
    ls.step(n=5)
    assert any(t.machine == "C-BS" and t.state == M.ASSIGNED and t.kind == M.GET_WORKPIECE
               for t in kb.tasks.values())


def test_a_task_taken_back_goes_to_no_other_robot_until_its_robot_has_provably_stopped_it():
    """The cancel of a task whose station went down is lost (its robot is cut off, or
    only its acknowledgement is): the robot may still run the task until its lease runs
    out, so the task waits, station back up or not, until the robot acknowledges the
    cancel, answers it with a result, or has been silent past its lease."""
    for proof in ("ack", "result", "silence", "league beacon"):
        ls = Lockstep(config=ServerConfig(prefill_caps=False), league=proof == "league beacon")
        kb, bs = bs_task_after_setup(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0)])
        first = next(a for a in ls.agents if a.number == bs.robot)
        others = [a for a in ls.agents if a is not first]
        first.ack = False                                      # nothing of it reaches the server but beacons
        if proof == "league beacon":       # a league robot: no LinkAck; its beacon says what it runs
            first.running = next(m for m in first.inbox if m.DESCRIPTOR.name == "AgentTask"
                                 and from_wire(m.task_id)[0] == bs.id and not m.cancel_task)
        ls.station_states["C-BS"] = "DOWN"
        ls.refbox.machines(ls.station_states)
        ls.step(n=3)
        assert kb.tasks[bs.id].state == M.PENDING and ls.server.tasks.stop_owed(bs.id) == first.number
        ls.station_states["C-BS"] = "IDLE"                     # back up at once
        ls.refbox.machines(ls.station_states)
        for _ in range(16):                                    # 8 s: the robot still heard, the cancel unanswered
            for a in ls.agents:
                a.beat()
            ls.step(dt=0.5)
        assert kb.tasks[bs.id].state == M.PENDING, f"{proof}: task given away while robot {first.number} may run it"
        assert first.cancels() and all(a.tasks() == [] or bs.id not in [t.task_id for t in a.tasks()]
                                       for a in others)
        if proof == "ack":
            first.ack = True                                   # the next copy of the cancel is acknowledged
            for _ in range(20):
                first.beat()
                ls.step(dt=0.5)
                if kb.tasks[bs.id].state == M.ASSIGNED:
                    break
        elif proof == "league beacon":
            first.running = None                               # it stopped: its next beacon says so
            first.beat()
            ls.step(n=2)
        elif proof == "result":
            first.result(bs.id, status="CANCELLED")
            ls.step(n=2)
        else:
            for _ in range(24):                                # 12 s silent: dropped, its lease over
                for a in others:
                    a.beat()
                ls.step(dt=0.5)
            assert kb.robots[first.number].status == M.LOST
        ls.step(n=2)
        assert kb.tasks[bs.id].state == M.ASSIGNED, f"{proof}: the task was not given out again"
        assert ls.server.tasks.stop_owed(bs.id) is None
        ls.close()


def test_a_task_taken_back_from_a_robot_on_a_slow_link_waits_for_the_longer_lease_it_was_granted():
    """The robot measured that the server's confirmations reach it 4.5 s late (2 s each way):
    its lease is 14.5 s (teamserver.links.leases), so its task, taken back while it is cut
    off (the cancel lost), goes to no other robot after the 10 s of silence that dropped a
    robot before, only once that lease is surely over."""
    ls = Lockstep(config=ALONE)
    kb, bs = bs_task_after_setup(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0)])
    first = next(a for a in ls.agents if a.number == bs.robot)
    others = [a for a in ls.agents if a is not first]
    first.ack = False
    first.status(stamp=500.0, lag=4.5)             # its last word: the cut begins
    ls.step(dt=0.1)
    heard_at = ls.clock.now()
    ls.station_states["C-BS"] = "DOWN"
    ls.refbox.machines(ls.station_states)
    ls.step(dt=0.1, n=3)
    assert kb.tasks[bs.id].state == M.PENDING and ls.server.tasks.stop_owed(bs.id) == first.number
    ls.station_states["C-BS"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    given = None
    while ls.clock.now() < heard_at + 20.0 and given is None:
        for a in others:
            a.beat()
        ls.step(dt=0.25)
        if kb.tasks[bs.id].state == M.ASSIGNED:
            given = ls.clock.now()
    assert (first.inbox and [(m.heard, m.lease) for m in first.inbox if m.DESCRIPTOR.name == "Heartbeat"
                             and m.HasField("lease")][-1] == (500.0, pytest.approx(14.5)))
    assert given is not None and heard_at + 14.5 < given < heard_at + 15.5, (heard_at, given)
    assert kb.tasks[bs.id].robot != first.number and kb.robots[first.number].status == M.LOST
    ls.close()


def test_a_product_planned_again_sends_no_robot_where_its_cancelled_pickup_may_still_run():
    """A product is planned again (a step of it failed) while one robot fetches its base
    at the BS and another its cap, and the BS robot's cancel goes unanswered (lost on the
    radio): the new plan's base pickup (a new task, a new id) goes to no robot, not even
    an idle one, while the first may still grab the base; neither robot whose pickup
    was cancelled gets new work until its result says what it holds."""
    ls = Lockstep(robots=4, config=ALONE)
    kb, bs = bs_task_after_setup(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0), (-4.5, 5.0, 0.0)])
    first = next(a for a in ls.agents if a.number == bs.robot)
    first.ack = False
    before = {a.number: len(a.tasks()) for a in ls.agents}
    ls.server.production.products.needs_repair(bs.product, "a step failed")
    for _ in range(24):                                        # 12 s: a planning round, the robots heard
        for a in ls.agents:
            a.beat()
        ls.step(dt=0.5)
    assert kb.tasks[bs.id].state == M.CANCELLED and bs.id in [c.task_id for c in first.cancels()]
    [again] = [t for t in kb.tasks.values() if t.machine == "C-BS" and t.kind == M.GET_WORKPIECE
               and t.product == bs.product and t.id != bs.id]
    assert again.state == M.PENDING, \
        f"the new pickup went to robot {again.robot} while robot {first.number} may run the old"
    cancelled = [a for a in ls.agents if any(kb.tasks[c.task_id].product == bs.product for c in a.cancels())]
    assert first in cancelled and len(cancelled) == 2           # the base's and the cap's robots
    assert all(len(a.tasks()) == before[a.number] for a in cancelled)
    assert not [k for a in ls.agents for k in task_kinds(a)[before[a.number]:] if k[2] == "C-BS"]
    for a in ls.agents:                                        # they stopped, empty-handed
        for c in a.cancels():
            if kb.tasks[c.task_id].kind != M.GO_TO:
                a.result(c.task_id, status="CANCELLED", holding=False)
    for _ in range(4):
        for a in ls.agents:
            a.beat()
        ls.step(dt=0.5)
    assert kb.tasks[again.id].state == M.ASSIGNED and ls.server.tasks.stop_owed(bs.id) is None
    ls.close()


def test_a_task_a_robot_says_it_runs_goes_to_no_other_robot_also_after_a_restart_of_the_server(tmp_path):
    """The server restarts after taking a task back (its cancel lost): it has forgotten
    the stop it was owed, but the robot's status says it still runs the task, so the
    task waits until the robot says it stopped (or falls silent past its lease)."""
    ls = Lockstep(config=ServerConfig(prefill_caps=False), state=str(tmp_path / "ts.sqlite"))
    kb, bs = bs_task_after_setup(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0)])
    first, wire = next(a for a in ls.agents if a.number == bs.robot), wire_id(bs)
    first.ack = False
    ls.station_states["C-BS"] = "DOWN"
    ls.refbox.machines(ls.station_states)
    ls.step(n=3)
    assert kb.tasks[bs.id].state == M.PENDING
    ls.restart()
    kb = ls.server.kb
    assert ls.server.tasks.stop_owed(bs.id) is None                # forgotten
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("PRODUCTION", "RUNNING", 30.0)
    ls.station_states["C-BS"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    for _ in range(16):                                            # 8 s: it says it runs the task
        for a in ls.agents:
            a.beat()
            a.status(state=2, task=wire) if a is first else a.status()
        ls.step(dt=0.5)
    assert kb.tasks[bs.id].state == M.PENDING, "task given away while a robot said it ran it"
    first.status()                                                 # stopped (the cancel repeated on each status)
    ls.step(n=3)
    assert kb.tasks[bs.id].state == M.ASSIGNED
    ls.close()


def test_a_prepared_station_going_down_keeps_its_task(tcp):
    ls = tcp
    kb, bs = bs_task_after_setup(ls, [(5.0, 1.2, 0.0), (-5.0, 5.5, 0.0), (-5.5, 5.0, 0.0)])  # one at the BS
    assert bs.prepared_at is not None                      # the station has its instruction
    ls.station_states["C-BS"] = "DOWN"
    ls.refbox.machines(ls.station_states)
    ls.step(n=3)
    assert kb.tasks[bs.id].state == M.ASSIGNED             # the base comes out after DOWN


@pytest.mark.parametrize("holding", [True, False], ids=["holds", "on-its-way"])
def test_work_that_frees_a_stuck_robot_goes_first(holding):
    """Robot 1 holds a base (or is on its way to pick it up) whose cap mount waits
    for its cap retrieval at C-CS2 (DOWN until now); the only free robot stands
    next to C-CS1 where another product's cap retrieval waits, yet it goes for the
    one that frees robot 1.  (On its way, robot 1 did not count: rcll2025 seed 2
    with 20 % loss, a robot fetched a product whose cap nobody had started on,
    and held it 100 s.)"""
    # (robot 1 fetches the base early: it would not while nobody can start the cap, test_ts_holding.py)
    ls = Lockstep(robots=2, config=ServerConfig(prefill_caps=False, dispatch=DispatchConfig(fetch_early=True)))
    place(ls, [(5.0, 1.2, 0.0), (-5.0, 5.5, 0.0)])
    production_setup(ls, [{"id": 1}], states={"C-CS2": "DOWN"})
    kb, d = ls.server.kb, ls.server.dispatcher
    ls.step(n=3)
    [get] = [t for t in kb.tasks.values() if t.machine == "C-BS" and t.state == M.ASSIGNED]
    assert get.robot == 1
    if holding:
        ls.agents[0].result(get.id, holding=True)                   # robot 1 holds the base
    ls.step(n=3)
    [retrieve] = [t for t in kb.tasks.values() if t.kind == M.RETRIEVE_CAP]
    assert retrieve.state == M.PENDING                              # C-CS2 is DOWN
    assert retrieve.id in d.holding.unblocking(0.0)
    # a second order: its cap retrieval at C-CS1 is right next to the free robot ...
    x, y = ls.server.production.world.positions()["C-CS1"][:2]
    ls.agents[1].pose = (x + 0.8, y, 0.0)
    ls.agents[1].status()
    grey = ls.refbox.ms.enum("CapColor").Value("CAP_GREY")
    ls.refbox.orders(ls.order_msgs + [dict(ls.order_msgs[0], id=2, delivery_gate=2, cap_color=grey)])
    ls.station_states["C-CS2"] = "IDLE"
    ls.refbox.machines(ls.station_states, RS_2016)
    ls.step(n=3)
    # ... but the retrieval that frees robot 1 goes first
    assert kb.tasks[retrieve.id].state == M.ASSIGNED and kb.tasks[retrieve.id].robot == 2
    assert not any(t.machine == "C-CS1" and t.state == M.ASSIGNED for t in kb.tasks.values())


def test_the_fleet_tells_how_long_a_robot_has_been_without_work():
    ls = Lockstep()
    production_setup(ls, [])                            # nothing to make: all three idle
    fleet = ls.server.dispatcher.fleet
    idle = fleet.idle_for()
    ls.clock.advance(4.0)
    assert fleet.idle_for() == pytest.approx(idle + 4.0)
    r = ls.server.kb.robots[1]
    r.holding = "P1/wp1"                                # holding a workpiece: not without work
    ls.server.kb.save_robot(r)
    for n in (2, 3):
        r = ls.server.kb.robots[n]
        r.task_id = 99
        ls.server.kb.save_robot(r)
    assert fleet.idle_for() == 0.0


def test_the_steps_of_a_product_whose_cap_waits_in_a_cap_station_go_first():
    """Product A's cap waits in C-CS1 (which takes no other product's cap until it is
    mounted); the only free robot stands next to C-CS2, where product B's cap
    retrieval could start, yet it fetches A's base."""
    ls = Lockstep(robots=1, config=ALONE)
    production_setup(ls, [])
    ls.step(n=2)
    kb, d = ls.server.kb, ls.server.dispatcher
    products = ls.server.production.products
    x, y = ls.server.production.world.positions()["C-CS2"][:2]
    ls.agents[0].pose = (x + 0.8, y, 0.0)
    ls.agents[0].status()
    ls.step()
    a, b = products.new("P", 1), products.new("P", 2)
    base = M.Task(kb.next_id("task"), M.GET_WORKPIECE,
                  {"machine": "C-BS", "side": M.OUTPUT, "base": "BASE_RED"}, product=a.id,
                  prepare={"machine": "C-BS", "bs": {"side": M.OUTPUT, "color": "BASE_RED"}},
                  locks=("C-BS",), releases=("C-BS",))
    retrieve = M.Task(kb.next_id("task"), M.RETRIEVE_CAP, {"machine": "C-CS2"}, product=b.id,
                      prepare={"machine": "C-CS2", "cs": {"operation": "RETRIEVE_CAP"}},
                      locks=("C-CS2", "C-CS2#cap"))
    for p, t in ((a, base), (b, retrieve)):
        kb.save_task(t)
        p.tasks = (t.id,)
        kb.save_product(p)
    d.matcher.assign(0.0)
    assert kb.tasks[retrieve.id].state == M.ASSIGNED      # nothing waits: the nearer one
    kb.tasks[retrieve.id].state, kb.tasks[retrieve.id].robot = M.PENDING, None
    ls.server.production.locks.release(b.id)
    robot = kb.robots[1]
    robot.task_id = None
    kb.save_robot(robot)
    ls.server.production.buffers.take("C-CS1", a.id)
    d.matcher.assign(0.0)
    assert kb.tasks[base.id].state == M.ASSIGNED and kb.tasks[base.id].robot == 1
    assert kb.tasks[retrieve.id].state == M.PENDING


def test_a_cap_retrieval_its_product_waits_for_goes_before_a_base_a_little_nearer():
    """Product A's rings are under way (it has none): its cap retrieval at C-CS2 is
    what it waits for next; the only free robot stands 3 m nearer to C-BS, where
    product B (same order) could fetch its first base, yet it starts A's cap."""
    ls = Lockstep(robots=1, config=ALONE)
    production_setup(ls, [])
    ls.step(n=2)
    kb, d = ls.server.kb, ls.server.dispatcher
    products = ls.server.production.products
    pos = ls.server.production.world.positions()
    (bx, by), (cx, cy) = pos["C-BS"][:2], pos["C-CS2"][:2]
    dist = ((bx - cx) ** 2 + (by - cy) ** 2) ** 0.5
    ux, uy = (bx - cx) / dist, (by - cy) / dist
    at = (dist + 3.0) / 2                    # 3 m nearer to C-BS than to C-CS2
    ls.agents[0].pose = (cx + ux * at, cy + uy * at, 0.0)
    ls.agents[0].status()
    ls.step()
    a, b = products.new("P", 1), products.new("P", 1)
    retrieve = M.Task(kb.next_id("task"), M.RETRIEVE_CAP, {"machine": "C-CS2"}, product=a.id,
                      prepare={"machine": "C-CS2", "cs": {"operation": "RETRIEVE_CAP"}},
                      locks=("C-CS2", "C-CS2#cap"))
    base = M.Task(kb.next_id("task"), M.GET_WORKPIECE,
                  {"machine": "C-BS", "side": M.OUTPUT, "base": "BASE_RED"}, product=b.id,
                  prepare={"machine": "C-BS", "bs": {"side": M.OUTPUT, "color": "BASE_RED"}},
                  locks=("C-BS",), releases=("C-BS",))
    for p, t in ((a, retrieve), (b, base)):
        kb.save_task(t)
        p.tasks = (t.id,)
        kb.save_product(p)
    d.matcher.assign(0.0)
    assert kb.tasks[retrieve.id].state == M.ASSIGNED and kb.tasks[retrieve.id].robot == 1
    assert kb.tasks[base.id].state == M.PENDING
