"""A robot cut off from the team server mid-task while the server may give its task to
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
from tests.support.games import PRODUCTION_KINDS

pytestmark = pytest.mark.slow   # a short whole game

CUT = 40.0          # s: longer than the team server's heartbeat timeout (10 s)


def test_a_robot_dropped_while_cut_off_has_stopped_its_task_so_no_task_runs_twice():
    # R1's link to the team server behind the fault layer (a cut far in the future: none yet)
    net = NetFaults(cuts=(("R1", 1e6, 1e6 + 1.0),))
    opts = GameOptions(seed=3, robots=3, setup=1.0, exploration=3.0, production=900.0, strategy="oracle", net=net)
    with LockstepGame(opts) as game:
        link, r1 = game.agents[1].link, game.agents[1]
        both: list[tuple[float, int, list[int]]] = []
        cuts: list[dict] = []           # one per cut: R1 cut off as it starts a production step

        def watch(g):
            now = g.clock.now()
            # robot -> the planned task it runs (a task given to another robot is a new assignment:
            # its wire id names the same task and the next attempt)
            by_task: dict[int, list[int]] = {}
            for n, a in g.agents.items():
                if a.run is not None and not a.run.done:
                    by_task.setdefault(from_wire(a.run.task_id)[0], []).append(n)
            both.extend((now, tid, ns) for tid, ns in by_task.items() if len(ns) > 1)
            run, cut = r1.run, cuts[-1] if cuts else None
            mine = run is not None and not run.done and cut is not None and from_wire(run.task_id)[0] == cut["task"]
            if cut is not None and "stopped" not in cut and not mine:
                cut["stopped"] = now                   # R1 is off the task (stopped it, or done)
            if cut is not None and "lost" not in cut and g.teamserver.snapshot()["robots"][1]["status"] == "LOST":
                cut["lost"], cut["ran_on"] = now, mine
            # a new cut once the last is over and R1 is back: as R1 starts a production step (the server
            # gives it, or the step that repairs it, to another robot when it drops R1); a step done
            # within the lease proves nothing
            back = cut is None or (now > cut["end"] and g.teamserver.snapshot()["robots"][1]["status"] == "ACTIVE")
            if back and not exercised() and run is not None and not run.done and run.kind in PRODUCTION_KINDS \
                    and (cut is None or from_wire(run.task_id)[0] != cut["task"]):
                cuts.append({"task": from_wire(run.task_id)[0], "wire": run.task_id, "start": now, "end": now + CUT})
                link.faults = dataclasses.replace(link.faults, cuts=((now, now + CUT),))

        def exercised() -> bool:           # a cut under which R1's step outlasted its lease
            return any("lost" in c and c["wire"] in r1.book.finished and not r1.book.finished[c["wire"]].successful
                       for c in cuts)
        game.hooks.append(watch)
        assert game.run_until(lambda g: any(c.get("ran_on") for c in cuts)
                              or exercised() and g.clock.now() > cuts[-1]["end"] + 10.0, limit=800.0), \
            f"R1 was never cut off and dropped in the middle of a step: {cuts}"
        for cut in cuts:
            if "lost" in cut:
                assert cut["lost"] - cut["start"] >= 10.0              # dropped after the heartbeat timeout ...
                # ... when R1 had already left the task (on main before the lease it still ran it)
                assert not cut["ran_on"] and cut["stopped"] <= cut["lost"], f"R1 still ran its task when dropped: {cut}"
        assert not both, f"two robots ran the same task at once: {both[:3]}"
        # the step that outlasted the lease: stopped, FAILED for the lease, told when back; R1 back at work
        cut = next(c for c in cuts if "lost" in c and not r1.book.finished[c["wire"]].successful)
        assert "lease" in r1.book.finished[cut["wire"]].outcome.text and cut["stopped"] - cut["start"] < 10.0
        assert game.teamserver.snapshot()["robots"][1]["status"] == "ACTIVE"
        assert not r1.server.delivery.unacknowledged
