"""A robot cut off from the team server mid-task while the server gives its task to
another robot: the task must not be done twice.  The server drops a robot it has not
heard for its heartbeat timeout and gives its task to another robot (a new assignment of
the same task: both robots would take a base for the same step);
the cut-off robot, which cannot hear that, stops the task before the server may do so
(its lease: the server's heartbeats say until when it heard the robot and how long it
waits), so at no time do two robots run the same task."""
import dataclasses

import pytest

from games import GameOptions, LockstepGame
from rll_bt.comm.faults import NetFaults
from teamserver.links.agents import from_wire

pytestmark = pytest.mark.slow   # a short whole game

CUT = 40.0          # s: longer than the team server's heartbeat timeout (10 s)


def test_a_task_given_away_while_its_robot_is_cut_off_is_not_run_twice():
    # R1's link to the team server behind the fault layer (a cut far in the future: none yet)
    net = NetFaults(cuts=(("R1", 1e6, 1e6 + 1.0),))
    opts = GameOptions(seed=3, robots=3, setup=1.0, exploration=3.0, production=240.0, strategy="oracle", net=net)
    with LockstepGame(opts) as game:
        link = game.agents[1].link
        seen: dict[int, set[int]] = {}              # task id -> robots that ran it
        both: list[tuple[float, int, list[int]]] = []
        cut: dict = {}

        def watch(g):
            now = g.clock.now()
            # robot -> the planned task it runs (a task given to another robot is a new assignment:
            # its wire id names the same task and the next attempt)
            runs = {n: from_wire(a.run.task_id)[0] for n, a in g.agents.items()
                    if a.run is not None and not a.run.done}
            for n, tid in runs.items():
                seen.setdefault(tid, set()).add(n)
            by_task: dict[int, list[int]] = {}
            for n, tid in runs.items():
                by_task.setdefault(tid, []).append(n)
            both.extend((now, tid, ns) for tid, ns in by_task.items() if len(ns) > 1)
            run = g.agents[1].run
            # the cut: as R1 starts fetching a base (a step the server puts back under the same id)
            if not cut and run is not None and not run.done and run.kind == "get_workpiece":
                cut.update(task=from_wire(run.task_id)[0], start=now)
                link.faults = dataclasses.replace(link.faults, cuts=((now, now + CUT),))
            if cut and "lost" not in cut and g.teamserver.snapshot()["robots"][1]["status"] == "LOST":
                cut["lost"] = now
                cut["r1_still_on_it"] = run is not None and not run.done and from_wire(run.task_id)[0] == cut["task"]
        game.hooks.append(watch)
        assert game.run_until(lambda g: "lost" in cut and len(seen.get(cut["task"], ())) > 1, limit=200.0), \
            f"R1 was not cut mid-fetch, or its task was never given to another robot: {cut}"
        game.run_until(lambda g: g.clock.now() > cut["start"] + CUT + 10.0, limit=60.0)
        tid = cut["task"]
        assert cut["lost"] - cut["start"] >= 10.0               # dropped after the heartbeat timeout
        assert len(seen[tid]) == 2                               # the task went to another robot ...
        assert not cut["r1_still_on_it"], "R1 still ran the task when the server gave it away"
        assert not both, f"two robots ran the same task at once: {both[:3]}"
        # R1 stopped and waited; back on the link, it told the server and took new work
        done = [r for wire, r in game.agents[1].book.finished.items() if from_wire(wire)[0] == tid]
        assert done and not done[0].successful and "lease" in done[0].outcome.text
        assert game.teamserver.snapshot()["robots"][1]["status"] == "ACTIVE"
        assert not game.agents[1].server.delivery.unacknowledged
