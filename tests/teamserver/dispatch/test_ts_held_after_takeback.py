"""A pickup taken back from its robot (its station went BROKEN or DOWN) or a pickup that
failed after the grab: what the robot's gripper holds then, and what the robot does next."""
from teamserver.knowledge import model as M
from tests.support.teamserver import RS_2016, Lockstep, production_setup, task_kinds
from tests.teamserver.dispatch.test_ts_dispatch import ALONE, place


def _first_robot_with_its_first_task():
    """Two robots far from every station, two orders: (ls, kb, the first robot, its first task)."""
    ls = Lockstep(robots=2, config=ALONE)
    place(ls, [(0.5, 5.5, 0.0), (-5.0, 5.5, 0.0)])                 # far from every station
    production_setup(ls, [{"id": 1}, {"id": 2, "delivery_gate": 2, "cap_color": 2}])
    ls.step(n=8)
    kb, agent = ls.server.kb, ls.agents[0]
    [first] = [t for t in kb.tasks.values() if t.state == M.ASSIGNED and t.robot == agent.number]
    return ls, kb, agent, first


def test_a_robot_whose_pickup_was_taken_back_gets_work_only_once_it_said_what_it_holds():
    """A pickup taken back (its station went BROKEN) may have been grabbed already: the
    robot gets no new work until its result says what it holds; holding something the
    server booked nowhere, it is told to discard it and is sent to feed no station
    (rcll2016 seed 10 at 672a03b: a robot given a RetrieveCap at once fed the product it
    had just grabbed to the cap station, which broke)."""
    ls, kb, agent, first = _first_robot_with_its_first_task()
    assert first.kind == M.RETRIEVE_CAP and first.prepared_at is None   # (a BS base waits too)
    ls.station_states[first.machine] = "BROKEN"
    ls.refbox.machines(ls.station_states)
    ls.step(n=3)
    assert first.id in [c.task_id for c in agent.cancels()]       # (and its parking before)
    before = len(agent.tasks())
    ls.step(n=6)
    assert len(agent.tasks()) == before                 # no work for it meanwhile
    agent.result(first.id, status="CANCELLED", holding=True)
    ls.step(n=4)
    robot = kb.robots[agent.number]
    assert robot.holding == "?"
    park = kb.tasks.get(robot.task_id) if robot.task_id is not None else None
    if park is not None:                                # it may park meanwhile
        assert park.kind == M.GO_TO
        agent.result(park.id)
    ls.step(n=4)
    kinds = [k for _, k, _ in task_kinds(agent)[before:]]
    assert kinds == ["discard"]                         # then it lets go, and feeds nothing
    ls.close()


def test_a_pickup_taken_back_after_its_robot_grabbed_the_workpiece_is_booked_done():
    """A station goes DOWN just after a robot took the workpiece off its output: the
    pickup (no PrepareMachine, so never *prepared*) is taken back, and the robot's
    CANCELLED result says it holds a workpiece.  That is the pickup's workpiece: the
    pickup is done and the product goes on from the gripper; the robot is not told to
    discard an "unknown" workpiece, and no robot is sent to the empty output again
    (rcll2016 seed 12 at 3b1cd15: C-CS1 went DOWN at 598.0 s, 1.4 s after robot 2 took
    the cap-less base of order 2's product; the base was discarded, the pickup sent
    again twice, GRAB_FAILED "no workpiece in the gripper" at 696 s and 738 s, the
    product abandoned and the base robot 1 had held since 308 s discarded too)."""
    ls, kb, agent, first = _first_robot_with_its_first_task()
    assert first.kind == M.RETRIEVE_CAP
    agent.result(first.id)                                          # the cap is in the station
    for _ in range(6):
        for a in ls.agents:
            a.beat()
        ls.step(dt=0.5)
    [pick] = [t for t in kb.tasks.values() if t.product == first.product
              and t.kind == M.GET_WORKPIECE and t.params.get("role") == "capless"]
    assert pick.state == M.ASSIGNED and pick.prepared_at is None
    grabber = next(a for a in ls.agents if a.number == pick.robot)
    ls.station_states[first.machine] = "DOWN"                       # just after the grab
    ls.refbox.machines(ls.station_states, RS_2016)
    ls.step(n=3)
    assert pick.id in [c.task_id for c in grabber.cancels()]        # taken back ...
    before = {a.number: len(a.tasks()) for a in ls.agents}
    grabber.result(pick.id, status="CANCELLED", holding=True)       # ... but it holds the base
    ls.step(n=3)
    robot = kb.robots[grabber.number]
    assert kb.tasks[pick.id].state == M.DONE
    wp = kb.workpieces[robot.holding]
    assert wp.product == first.product and wp.location == f"robot:{grabber.number}"
    ls.station_states[first.machine] = "IDLE"                       # back up
    ls.refbox.machines(ls.station_states, RS_2016)
    for _ in range(6):
        for a in ls.agents:
            a.beat()
        ls.step(dt=0.5)
    new = [k for a in ls.agents for k in task_kinds(a)[before[a.number]:] if k[1] != "go_to"]
    assert not [k for k in new if k[1] == "get_workpiece" and k[2] == first.machine], new
    assert [k[1] for k in task_kinds(grabber)[before[grabber.number]:] if k[1] != "go_to"] == ["discard"]
    assert not [p for p in kb.products.values() if p.id != first.product and p.order_id == 0
                and p.state == "ACTIVE"]                            # no clean-up of an "unknown"
    ls.close()


def test_a_robot_whose_retrieve_cap_failed_holding_the_carrier_discards_it_and_feeds_nothing():
    """A RetrieveCap that fails after the grab from the shelf (its cap station went
    DOWN: MACHINE_BROKEN) leaves the cap carrier in the gripper, booked nowhere: the
    robot discards it (processes game of seed 1 at 53618cd: the robot, empty in the
    server's books, was given a base pickup, which its tree took as done with the
    carrier in the gripper, and fed that capped base to a ring station: BROKEN)."""
    ls, kb, agent, first = _first_robot_with_its_first_task()
    assert first.kind == M.RETRIEVE_CAP
    before = len(agent.tasks())
    agent.result(first.id, status="FAILED", error="MACHINE_BROKEN", holding=True)
    ls.step(n=4)
    assert kb.robots[agent.number].holding == "?"
    kinds = [k for _, k, _ in task_kinds(agent)[before:]]
    assert kinds and set(kinds) <= {"discard", "go_to"} and "discard" in kinds
    ls.close()
