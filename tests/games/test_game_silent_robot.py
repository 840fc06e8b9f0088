"""A robot cut off from the team server mid-task while the server may give its task to
another robot: the task must not be done twice.  The server drops a robot it has not
heard for its heartbeat timeout and gives its task to another robot (a new assignment of
the same task: both robots would take a base for the same step);
the cut-off robot, which cannot hear that, stops the task before the server may do so
(its lease: the server's heartbeats say until when it heard the robot and how long it
waits), so at no time do two robots run the same task."""
import dataclasses
import math

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
            # within the lease, or failed at once for another reason, proves nothing; nor does a step
            # R1 has not begun under a lease the server renewed (back from a cut, it begins none before)
            back = cut is None or (now > cut["end"] and g.teamserver.snapshot()["robots"][1]["status"] == "ACTIVE")
            if back and not exercised() and run is not None and not run.done and run.kind in PRODUCTION_KINDS \
                    and run.ticks > 0 and not r1.server.lease.expired(now) \
                    and (cut is None or from_wire(run.task_id)[0] != cut["task"]):
                cuts.append({"task": from_wire(run.task_id)[0], "wire": run.task_id, "start": now, "end": now + CUT})
                link.faults = dataclasses.replace(link.faults, cuts=((now, now + CUT),))

        def exercised() -> bool:           # a cut under which R1's step outlasted its lease
            return any("lost" in c and c["wire"] in r1.book.finished and not r1.book.finished[c["wire"]].successful
                       and "lease" in r1.book.finished[c["wire"]].outcome.text for c in cuts)
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
        # (its lease: 10 s and the lag it measured, about 1 s on this perfect link, after its
        # last status the server confirmed)
        cut = next(c for c in cuts if "lost" in c and c["wire"] in r1.book.finished
                   and "lease" in r1.book.finished[c["wire"]].outcome.text)
        assert not r1.book.finished[cut["wire"]].successful and cut["stopped"] - cut["start"] < 12.0
        assert game.teamserver.snapshot()["robots"][1]["status"] == "ACTIVE"
        assert not r1.server.delivery.unacknowledged


def test_a_task_taken_back_under_a_cut_is_not_given_out_again_while_its_robot_may_still_run_it():
    """A robot is cut off on its way to fetch from a station that goes DOWN for 2 s: the
    team server takes the task back (the cancel is lost in the cut) and the station is
    soon up again.  The robot goes on with the task until its lease runs out, so the
    server gives the task to nobody (nor to the cut robot again, which would not hear it)
    until the robot is provably off it; then another robot does it."""
    net = NetFaults(cuts=tuple((f"R{n}", 1e6, 1e6 + 1.0) for n in (1, 2, 3)))     # cuts set below
    opts = GameOptions(seed=7, robots=3, setup=1.0, exploration=3.0, production=300.0, strategy="oracle", net=net)
    with LockstepGame(opts) as game:
        kb = game.teamserver.server.kb

        def on_the_way(g):      # (robot, task): a fetch from a station still 2 m away, another robot free
            if g.refbox.status().phase != "PRODUCTION":
                return None
            free = [r.number for r in kb.active_robots() if r.task_id is None
                    or kb.tasks[r.task_id].kind == "go_to"]
            for n, a in g.agents.items():
                t = kb.tasks.get(from_wire(a.run.task_id)[0]) if a.run is not None and not a.run.done else None
                if t is None or t.state != "ASSIGNED" or t.prepared_at is not None or a.run.ticks == 0 \
                        or t.kind not in ("get_workpiece", "retrieve_cap") or not set(free) - {n}:
                    continue
                st, pose = g.refbox.stations()[t.machine].pose, g.world.robot_pose("CYAN", n)
                if math.hypot(st.x - pose.x, st.y - pose.y) > 2.0:
                    return n, t
            return None
        assert game.run_until(on_the_way, limit=120.0), "no robot went to fetch from afar with another one free"
        n, task = on_the_way(game)
        wire, start = game.agents[n].run.task_id, game.clock.now()
        link = game.agents[n].link
        link.faults = dataclasses.replace(link.faults, cuts=((start, start + 20.0),))
        game.station_down(task.machine, 2.0)
        early: list = []

        def watch(g):       # the task out under a new assignment while the cut robot still runs the old one
            run = g.agents[n].run
            if task.state == "ASSIGNED" and task.attempts > from_wire(wire)[1] and run is not None \
                    and not run.done and run.task_id == wire:
                early.append((round(g.clock.now() - start, 1), task.robot))
        game.hooks.append(watch)
        assert game.run_until(lambda g: task.state == "PENDING", limit=2.0), "the task was not taken back"
        assert game.run_until(lambda g: task.state in ("ASSIGNED", "DONE") and task.robot != n, limit=30.0), \
            f"task {task.id} was not given to another robot: {task.state}, robot {task.robot}"
        assert not early, f"task {task.id} given out again while robot {n} still ran it: {early[:3]}"
        assert game.clock.now() - start >= 9.0                 # R ran it until its lease was over ...
        old = game.agents[n].book.finished[wire]               # ... then stopped it
        assert not old.successful and "lease" in old.outcome.text
