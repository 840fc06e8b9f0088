"""A robot about to finish a task that leaves its gripper empty gets its next task
before the current one ends (on a radio with 2 s of delay the round trip between
two tasks costs 4 s): queued behind it (TaskDetail ``after``), started once it
succeeded, back in the pool when it did not."""
import pytest

from teamserver.knowledge import model as M
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, production_setup, task_kinds

BUSY = 2


@pytest.fixture
def ls():
    """Three robots and two products (P1 capped black at C-CS2, P2 grey at C-CS1); robot 1
    retrieves P1's cap at C-CS2, robot 3, which had P2's, drops out: that retrieval waits.
    Robot 2, on its way to P1's base, drops out too (the queued task is then the only other work)."""
    ls = Lockstep(robots=3, config=ServerConfig(max_products=2, prefill_caps=False))
    for a, pose in zip(ls.agents, [(3.0, 2.8, 0.0), (5.0, 1.3, 0.0), (5.0, 3.2, 0.0)]):
        a.pose = pose
        a.status()
    grey = ls.refbox.ms.enum("CapColor").Value("CAP_GREY")
    production_setup(ls, [{"id": 1}, {"id": 2, "cap_color": grey}])
    ls.step(n=5)
    kb = ls.server.kb
    assert [k[1:] for k in task_kinds(ls.agents[0])] == [("retrieve_cap", "C-CS2")]
    assert [k[1:] for k in task_kinds(ls.agents[2])] == [("retrieve_cap", "C-CS1")]
    ls.waiting = task_kinds(ls.agents[2])[0][0]
    ls.server.dispatcher.dropouts.drop(kb.robots[3], "switched off")
    ls.server.dispatcher.dropouts.drop(kb.robots[2], "switched off")
    ls.step()
    assert kb.tasks[ls.waiting].state == M.PENDING
    yield ls
    ls.close()


def prepares(ls, machine):
    return [p for p in ls.refbox.received if p.DESCRIPTOR.name == "PrepareMachine" and p.machine == machine]


def queued_behind(ls):
    """Robot 1 says it runs its retrieval at C-CS2: the waiting task is queued behind it."""
    kb, r1 = ls.server.kb, ls.agents[0]
    current = r1.tasks()[-1]
    r1.status(state=BUSY, task=current.wire_id)
    ls.step(n=3)
    assert kb.tasks[ls.waiting].after == current.task_id
    return kb, r1, current


def queued(agent):
    """(task id, TaskDetail.after) of the tasks ``agent`` got."""
    return [(v.task_id, v.detail.after if v.detail.HasField("after") else None) for v in agent.tasks()]


def test_a_robot_at_the_end_of_its_task_gets_the_next_one_queued_behind_it(ls):
    kb, r1 = ls.server.kb, ls.agents[0]
    current = r1.tasks()[-1]
    ls.step(n=3)
    assert queued(r1) == [(current.task_id, None)]          # it has not said it runs its task there
    before = len(prepares(ls, "C-CS1"))
    r1.status(state=BUSY, task=current.wire_id)              # docked at C-CS2, running it
    ls.step(n=3)
    assert queued(r1) == [(current.task_id, None), (ls.waiting, current.wire_id)]
    nxt = kb.tasks[ls.waiting]
    assert nxt.state == M.ASSIGNED and nxt.robot == 1 and nxt.after == current.task_id
    assert kb.robots[1].task_id == current.task_id           # its current task stays its own
    assert len(prepares(ls, "C-CS1")) == before              # nobody goes to C-CS1 yet
    r1.result(current.task_id)
    ls.step(n=2)
    assert kb.robots[1].task_id == ls.waiting and nxt.after is None and nxt.state == M.ASSIGNED
    assert r1.cancels() == []


def test_the_queued_task_goes_back_to_the_pool_when_the_one_before_fails(ls):
    kb, r1, current = queued_behind(ls)
    r1.result(current.task_id, status="FAILED", error="NAVIGATION_FAILED")
    ls.step(n=2)
    assert kb.tasks[ls.waiting].state == M.PENDING and kb.tasks[ls.waiting].after is None
    assert ls.waiting in [c.task_id for c in r1.cancels()]
    assert kb.tasks[kb.robots[1].task_id].kind == M.RETRIEVE_CAP            # the step tried again
    assert kb.tasks[kb.robots[1].task_id].machine == "C-CS2"
    ls.step(n=3)                # nothing is queued behind a task the robot has not said it runs
    assert kb.tasks[ls.waiting].state == M.PENDING


def test_a_queued_task_the_robot_refuses_goes_back_to_the_pool(ls):
    """The robot never had the task before it (restarted meanwhile): it refuses
    the queued one as not begun, and the server gives it out anew."""
    kb, r1, current = queued_behind(ls)
    first = r1.tasks()[-1].wire_id
    r1.result(ls.waiting, status="FAILED", error="NOT_RUNNING", text="the task before it did not succeed")
    ls.step()
    assert kb.robots[1].task_id == current.task_id and kb.tasks[current.task_id].state == M.ASSIGNED
    # given out anew: a new assignment (still to this robot, still finishing), not a failure of the step
    assert r1.tasks()[-1].task_id == ls.waiting and r1.tasks()[-1].wire_id != first
    assert kb.tasks[ls.waiting].after == current.task_id
    assert not kb.products[kb.tasks[ls.waiting].product].repair


def test_a_queued_task_of_a_dropped_robot_goes_back_to_the_pool(ls):
    kb, r1, current = queued_behind(ls)
    ls.server.dispatcher.dropouts.drop(kb.robots[1], "switched off")
    ls.step()
    assert kb.tasks[ls.waiting].state == M.PENDING and kb.tasks[ls.waiting].robot is None


@pytest.mark.parametrize("outcome", ["SUCCEEDED", "FAILED"])
def test_the_step_that_carries_a_workpiece_is_queued_behind_its_pickup(outcome):
    """A C1 whose ring costs nothing: its ring mount is ready but for the base's pickup,
    and goes to the robot that picks the base up anyway: queued behind the pickup."""
    ls = Lockstep(robots=2, config=ServerConfig(prefill_caps=False))
    try:
        for a, pose in zip(ls.agents, [(5.0, 1.3, 0.0), (1.0, 5.0, 0.0)]):
            a.pose = pose
            a.status()
        production_setup(ls, [{"id": 1, "complexity": 1, "rings": ["RING_GREEN"]}])
        ls.step(n=5)
        kb, r1 = ls.server.kb, ls.agents[0]
        pickup = r1.tasks()[-1]
        assert (pickup.kind, pickup.get_workpiece.machine) == ("get_workpiece", "C-BS")
        r1.status(state=BUSY, task=pickup.wire_id)
        ls.step(n=3)
        mount = r1.tasks()[-1]
        assert (mount.kind, mount.mount_ring.machine) == ("mount_ring", "C-RS1")
        assert mount.detail.after == pickup.wire_id and kb.tasks[mount.task_id].after == pickup.task_id
        if outcome == "SUCCEEDED":
            r1.result(pickup.task_id, holding=True)
            ls.step(n=2)
            assert kb.robots[1].task_id == mount.task_id and kb.tasks[mount.task_id].holder == 1
        else:
            r1.result(pickup.task_id, status="FAILED", error="GRAB_FAILED")
            ls.step(n=2)
            m = kb.tasks[mount.task_id]
            assert m.state == M.PENDING and m.holder is None and m.after is None
            assert mount.task_id in [c.task_id for c in r1.cancels()]
    finally:
        ls.close()


def consistent(kb):
    """Every robot's task is an assigned task of its own; every other assigned task of a
    robot is queued behind that one."""
    for r in kb.robots.values():
        if r.task_id is not None:
            t = kb.tasks[r.task_id]
            assert t.state == M.ASSIGNED and t.robot == r.number and t.after is None, (r, t)
    for t in kb.tasks.values():
        if t.state == M.ASSIGNED and kb.robots[t.robot].task_id != t.id:
            assert t.after is not None and t.after == kb.robots[t.robot].task_id, t


def test_a_queued_task_taken_back_and_given_out_again_runs_as_any_other(ls):
    """Its station went DOWN while it was queued (taken back), and it is given out again:
    a task of its own, not queued behind one that finished (the hardware game of seed 2
    at 0986293 left a robot bound to such a task, idle, for 600 s)."""
    from tests.support.teamserver import RS_2016
    kb, r1, current = queued_behind(ls)
    ls.station_states["C-CS1"] = "DOWN"
    ls.refbox.machines(ls.station_states, RS_2016)
    ls.step(n=3)
    assert kb.tasks[ls.waiting].state == M.PENDING and kb.tasks[ls.waiting].after is None
    consistent(kb)
    r3 = ls.agents[2]                         # robot 3 is back, idle, beside C-CS1
    r3.hello(restarted=True)
    r3.status()
    ls.station_states["C-CS1"] = "IDLE"
    ls.refbox.machines(ls.station_states, RS_2016)
    for _ in range(20):
        ls.step()
        consistent(kb)
    t = kb.tasks[ls.waiting]
    assert t.state == M.ASSIGNED and t.robot == 3 and kb.robots[3].task_id == ls.waiting
    assert not r3.tasks()[-1].detail.HasField("after") and r3.tasks()[-1].task_id == ls.waiting

