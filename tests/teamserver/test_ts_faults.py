"""Faults: robots that drop out and come back, a team server killed and restarted."""
from teamserver.knowledge import model as M
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep, production_setup, task_kinds


def beat_all_but(ls, silent, seconds, dt=0.5):
    for _ in range(int(seconds / dt)):
        for a in ls.agents:
            if a.number not in silent:
                a.beat()
        ls.step(dt=dt)


def test_a_silent_robot_is_dropped_and_its_task_reassigned():
    ls = Lockstep(config=ServerConfig(prefill_caps=False))
    ls.server.config.dispatch.heartbeat_timeout = 4.0
    for a, pose in zip(ls.agents, [(5.0, 1.6, 0.0), (0.5, 5.5, 0.0), (1.0, 5.0, 0.0)]):
        a.pose = pose
    production_setup(ls, [{"id": 1}])
    kb = ls.server.kb
    [(tid, _, _)] = [k for k in task_kinds(ls.agents[0]) if k[2] == "C-BS"]
    beat_all_but(ls, {1}, 3.0)
    assert kb.robots[1].status == M.ACTIVE                     # not yet
    beat_all_but(ls, {1}, 2.0)
    assert kb.robots[1].status == M.LOST
    t = kb.tasks[tid]
    assert t.state == M.ASSIGNED and t.robot in (2, 3)         # the same step, another robot
    assert any(m.task_id == tid for m in ls.agents[t.robot - 1].tasks())
    # a late result of the dropped robot changes nothing
    ls.agents[0].result(tid)
    ls.step()
    assert kb.tasks[tid].state == M.ASSIGNED and kb.tasks[tid].robot != 1


def test_a_robot_that_comes_back_gets_the_machine_map_at_once():
    ls = Lockstep()
    ls.server.config.dispatch.heartbeat_timeout = 2.0
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("EXPLORATION", "RUNNING", 0)
    ls.step()
    ls.agents[1].observe("C-RS2", zone=7, zconf=0.95)
    beat_all_but(ls, {3}, 3.0)
    assert ls.server.kb.robots[3].status == M.LOST
    explore_before = ls.server.kb.robots[3].task_id
    assert explore_before is None
    ls.agents[2].inbox.clear()
    ls.agents[2].beat()
    ls.step()                                                  # one tick
    names = [m.DESCRIPTOR.name for m in ls.agents[2].inbox]
    assert "MachineMap" in names and "GamePhase" in names
    mm = [m for m in ls.agents[2].inbox if m.DESCRIPTOR.name == "MachineMap"][0]
    known = {k.name: k.zone for k in mm.machines}
    assert known["C-RS2"] == 7 and known["M-RS2"] == 19
    assert ls.server.kb.robots[3].status == M.ACTIVE


def test_the_team_server_resumes_from_its_database(tmp_path):
    state = str(tmp_path / "ts.sqlite")
    ls = Lockstep(state=state)
    production_setup(ls, [{"id": 1, "complexity": 1, "rings": ["RING_ORANGE"]}])
    kb = ls.server.kb
    ls.agents[1].observe("M-CS1", zone=17, zconf=0.8, lights=5, lconf=0.7)
    ls.step()
    # finish a few tasks, leave others assigned
    done = 0
    for a in ls.agents:
        for t in a.tasks()[:1]:
            a.result(t.task_id, holding=t.WhichOneof("kind") == "get_workpiece")
            done += 1
    ls.step(n=3)
    before_tasks = {i: t.to_dict() for i, t in kb.tasks.items()}
    before_obs = {(m, p): kb.estimate(m, p) for m in kb.machines for p in (M.ZONE, M.LIGHT)}
    before_products = {i: p.to_dict() for i, p in kb.products.items()}
    before_locks = dict(kb.get("locks"))
    count = kb.observation_count
    assert sum(1 for t in before_tasks.values() if t["state"] == M.DONE) == done
    assigned = {t["robot"]: i for i, t in before_tasks.items() if t["state"] == M.ASSIGNED}
    assert assigned

    ls.restart()
    kb2 = ls.server.kb
    assert kb2 is not kb
    assert {i: t.to_dict() for i, t in kb2.tasks.items()} == before_tasks
    assert {(m, p): kb2.estimate(m, p) for m in kb2.machines
            for p in (M.ZONE, M.LIGHT)} == before_obs
    assert {i: p.to_dict() for i, p in kb2.products.items()} == before_products
    assert kb2.get("locks") == before_locks and kb2.observation_count == count
    assert ls.server.color == "CYAN"
    # the robots reconnect: each gets its running task again, nothing is planned twice
    for a in ls.agents:
        a.inbox.clear()
        a.hello()
    ls.refbox.game_state("PRODUCTION", "RUNNING", 30.0)
    ls.step(n=2)
    for number, tid in assigned.items():
        a = ls.agents[number - 1]
        assert tid in [t.task_id for t in a.tasks() + a.parks()]
    assert len(kb2.products) == len(before_products)
    # and the game goes on to the delivery
    answered = {a.number: 0 for a in ls.agents}
    for _ in range(400):
        for a in ls.agents:
            a.beat()
            tasks = a.tasks()
            for t in tasks[answered[a.number]:]:
                a.result(t.task_id, holding=t.WhichOneof("kind") == "get_workpiece")
            answered[a.number] = len(tasks)
        ls.step(dt=0.5)
        if any(p.state == "DELIVERED" for p in kb2.products.values()):
            break
    assert any(p.state == "DELIVERED" for p in kb2.products.values())
    ls.close()
