"""The task link under network faults: tasks and cancels repeated until the robot
acknowledges them, not to a robot whose task it no longer is; results acknowledged."""
from rll_bt.comm.reliable import AT_SUCCEEDED, AT_TASK, agent_task_what
from teamserver.knowledge import model as M
from teamserver.links.agents import from_wire, wire_id
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, production_setup


def _beat(ls, seconds, dt=0.5):
    for _ in range(int(seconds / dt)):
        for a in ls.agents:
            a.beat()
        ls.step(dt=dt)


def _copies(agent, tid):
    return [m for m in agent.inbox if m.DESCRIPTOR.name == "AgentTask" and not m.cancel_task
            and from_wire(m.task_id)[0] == tid]


def _first_task(ls):
    production_setup(ls, [{"id": 1}])
    kb = ls.server.kb
    t = next(t for t in kb.tasks.values() if t.state == M.ASSIGNED and t.kind != M.GO_TO)
    return kb, t, ls.agents[t.robot - 1]


def test_a_task_the_robot_does_not_acknowledge_is_repeated_with_backoff_then_not_once_acknowledged():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    for a in ls.agents:
        a.ack = False                                  # acknowledgements lost
    kb, t, agent = _first_task(ls)
    assert len(_copies(agent, t.id)) == 1
    _beat(ls, 8.0)
    assert len(_copies(agent, t.id)) == 4              # again after 1, 2 and 4 s
    assert ls.server.tasks.reliable.counts["repeated"] >= 3
    agent.ack = True
    _beat(ls, 8.5)                                     # the next copy is acknowledged ...
    n = len(_copies(agent, t.id))
    _beat(ls, 20.0)
    assert len(_copies(agent, t.id)) == n              # ... and it is not repeated any more
    assert ls.server.tasks.reliable.pending(t.robot) == []


def test_a_cancelled_or_reassigned_task_is_not_repeated_to_its_old_robot():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    ls.server.config.dispatch.heartbeat_timeout = 4.0
    for a in ls.agents:
        a.ack = False
    kb, t, agent = _first_task(ls)
    old = t.robot
    for _ in range(12):                                # the robot falls silent: dropped, its task goes elsewhere
        for a in ls.agents:
            if a is not agent:
                a.beat()
        ls.step(dt=0.5)
    assert kb.robots[old].status == M.LOST and kb.tasks[t.id].robot != old
    n = len(_copies(agent, t.id))
    agent.beat()                                       # back: no copy of the task that is not its own
    _beat(ls, 10.0)
    assert len(_copies(agent, t.id)) == n
    assert all(from_wire(m.task_id)[0] != t.id or agent_task_what(m) != AT_TASK
               for m in ls.server.tasks.reliable.pending(old))


def test_results_are_acknowledged():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    kb, t, agent = _first_task(ls)
    wire = wire_id(t)
    agent.result(t.id)
    ls.step(n=2)
    assert kb.tasks[t.id].state == M.DONE
    assert (8000, 502, (wire << 3) | AT_SUCCEEDED) in [(i.comp_id, i.msg_type, i.id) for m in agent.acks
                                                       for i in m.items]
    agent.result(t.id)                                  # a repeat (the ack was lost): acknowledged again
    ls.step(n=2)
    assert sum(i.id == (wire << 3) | AT_SUCCEEDED for m in agent.acks for i in m.items) == 2
    assert ls.server.link._outcomes == {}               # the repeat's TaskOutcome is not kept either


def test_a_robot_back_on_a_new_connection_gets_the_cancel_before_the_next_task():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    kb, t, agent = _first_task(ls)
    robot = kb.robots[t.robot]
    agent.ack = False                                  # nothing of what follows is acknowledged
    ls.server.tasks.cancel(t, "test")
    t.state = M.CANCELLED
    robot.task_id = None
    ls.server.tasks.flush()
    follow = next(x for x in kb.tasks.values() if x.state == M.PENDING and x.kind != M.GO_TO)
    ls.server.dispatcher.fleet.assign(follow, robot)
    ls.server.tasks.flush()
    ls.step()
    agent.inbox.clear()
    agent.hello()                                      # a new connection: what was on the old one is lost
    ls.step()
    order = [("cancel" if m.cancel_task else "task", from_wire(m.task_id)[0]) for m in agent.inbox
             if m.DESCRIPTOR.name == "AgentTask"]
    assert order.index(("cancel", t.id)) < order.index(("task", follow.id))
    details = [i for i, m in enumerate(agent.inbox) if m.DESCRIPTOR.name == "TaskDetail"
               and from_wire(m.task_id)[0] == follow.id]
    tasks = [i for i, m in enumerate(agent.inbox) if m.DESCRIPTOR.name == "AgentTask" and not m.cancel_task
             and from_wire(m.task_id)[0] == follow.id]
    assert details and tasks and details[0] == tasks[0] - 1      # the repeat with its TaskDetail just before


def test_every_repeat_of_a_task_comes_after_its_task_detail():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    for a in ls.agents:
        a.ack = False
    kb, t, agent = _first_task(ls)
    _beat(ls, 4.0)
    at = [i for i, m in enumerate(agent.inbox) if m.DESCRIPTOR.name == "AgentTask" and not m.cancel_task
          and from_wire(m.task_id)[0] == t.id]
    assert len(at) == 3
    before = [agent.inbox[i - 1] for i in at]
    assert all(d.DESCRIPTOR.name == "TaskDetail" and d.task_id == agent.inbox[at[0]].task_id for d in before)


def test_robots_of_the_league_get_no_acknowledgements_and_no_repeats():
    """rll-bt teamserver --robots agenttask: the robots know only the league's messages."""
    ls = Lockstep(config=ServerConfig(prefill_caps=False, robots="agenttask"))
    for a in ls.agents:
        a.ack = False
    kb, t, agent = _first_task(ls)
    _beat(ls, 8.0)
    assert len(_copies(agent, t.id)) == 1 and ls.server.tasks.reliable.pending() == []
    agent.result(t.id)
    ls.step(n=2)
    assert kb.tasks[t.id].state == M.DONE
    assert not [m for a in ls.agents for m in a.inbox if m.DESCRIPTOR.name in ("LinkAck", "TaskDetail")]
