"""Whole games on a lossy radio: points, tasks repeated, lost and done twice.

For every seed whole lockstep games are played (three robots, oracle
perception, Algorithm 1 exploration, SETUP shortened to 10 s), each robot's
team-server link behind the fault layer (``rll-bt sim --net-loss P
--net-delay 2 --net-jitter 0.2``; both ways, TCP semantics: a lost segment
costs a retransmission):

- ``clean``: a perfect network, the reference;
- ``loss 0 %``, ``loss 10 %``, ``loss 20 %``: 2 s delay, 0.2 s jitter, that loss;
  for rcll2025 only clean and 20 %.

Measured per game: points (and the share of the clean game's on the same
seed), task messages repeated by the team server (tasks and cancels not yet
acknowledged) and results repeated by the agents, robots dropped by the team
server (silent for its heartbeat timeout), tasks lost (a task the server
sent that its robot never got, or a final result the robot made that the
server never acknowledged, more than 30 s before the end) and tasks done
twice (an assignment's AgentTask id started more than once: a task given
to another robot, or again after a cancel, is a new assignment with a new id;
or one planned task run by two robots at the same moment, as when a robot the
server dropped as silent still runs the task the server gave another).

    .venv/bin/python benchmarks/network_faults.py [--seeds 10] [--jobs 2] [--json FILE]
                                                  [--profiles rcll2016,rcll2025] [--levels clean,0,10,20]

Games run in the order that gives the aim's numbers first (per seed: clean
and 20 %), and every finished game is appended to ``--json`` at once, so a
run cut short still reports what it played (``--render FILE`` prints the
tables of such a file).  Aim: at 20 % loss and 2 s delay at least 80 % of the
clean game's points on every seed, no crash, 0 tasks lost, 0 done twice.
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import subprocess
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

from games.batch import fmt, mean
from games.options import GameOptions
from rll_bt.comm.faults import NetFaults
from rll_bt.comm.reliable import AT_TASK, agent_task_what
from teamserver.links.agents import from_wire

DELAY, JITTER = 2.0, 0.2
LEVELS = {"clean": None, "0": 0.0, "10": 0.1, "20": 0.2}
LATE = 30.0        # s before the end: what is on its way then is not counted lost


def options(profile: str, seed: int, level: str) -> GameOptions:
    loss = LEVELS[level]
    net = NetFaults() if loss is None else NetFaults(loss=loss, delay=DELAY, jitter=JITTER)
    return GameOptions(profile=profile, seed=seed, net=net)


class Ledger:
    """What the agents got and started, what the team server sent, who it dropped."""

    def __init__(self, game):
        self.game = game
        self.sent: dict[int, tuple[int, float]] = {}      # task id -> (robot, first sent)
        self.got: set[tuple[int, int]] = set()            # (robot, task id) that reached the agent
        self.starts: Counter[int] = Counter()
        self.drops = 0
        self.at_once: set[int] = set()                    # planned tasks two robots ran at once
        self._status: dict[int, str] = {}
        for agent in game.agents.values():
            self._watch(agent)
        ts = game.teamserver.server
        to_robot = ts.tasks.to_robot

        def sending(robot, msg):
            if robot is not None and msg.DESCRIPTOR.name == "AgentTask" and agent_task_what(msg) == AT_TASK:
                self.sent.setdefault(int(msg.task_id), (robot.number, game.clock.now()))
            to_robot(robot, msg)
        ts.tasks.to_robot = sending
        game.hooks.append(self._round)

    def _watch(self, agent) -> None:
        on_task = agent._on_agent_task
        number = agent.config.robot_id

        def got(task):
            if agent_task_what(task) == AT_TASK:
                self.got.add((number, int(task.task_id)))
            on_task(task)
        agent._on_agent_task = got
        agent.observers.append(self)

    def task_started(self, agent, run) -> None:
        self.starts[int(run.task_id)] += 1

    def _round(self, game) -> None:
        running: dict[int, int] = {}                      # planned task -> robots running it now
        for a in game.agents.values():
            if a.run is not None and not a.run.done:
                tid = from_wire(a.run.task_id)[0]
                running[tid] = running.get(tid, 0) + 1
        self.at_once |= {tid for tid, n in running.items() if n > 1}
        for n, r in game.teamserver.server.kb.robots.items():
            if self._status.get(n) == "ACTIVE" and r.status == "LOST":
                self.drops += 1
            self._status[n] = r.status

    def numbers(self) -> dict:
        game = self.game
        end = game.clock.now()
        never_got = [tid for tid, (robot, t) in self.sent.items()
                     if t < end - LATE and (robot, tid) not in self.got]
        unacked = [int(m.task_id) for a in game.agents.values() for m in a.server.delivery.unacknowledged
                   if m.task_id in a.book.finished and a.book.finished[m.task_id].outcome.stamp < end - LATE]
        ts = game.teamserver.server
        return {"tasks_sent": len(self.sent), "task_msgs_repeated": ts.tasks.reliable.counts["repeated"],
                "results_repeated": sum(a.server.delivery.reliable.counts["repeated"] for a in game.agents.values()),
                "robots_dropped": self.drops, "lost": len(never_got) + len(unacked),
                "lost_ids": sorted(never_got + unacked),
                "done_twice": sum(1 for n in self.starts.values() if n > 1) + len(self.at_once),
                "two_at_once": sorted(self.at_once),
                "lease_expiries": sum(a.server.lease.expiries for a in game.agents.values()),
                "link": {n: dict(getattr(a.link, "counts", {})) for n, a in game.agents.items()}}


def play(item: tuple[str, int, str]) -> dict:
    profile, seed, level = item
    from games.lockstep import LockstepGame
    from rll_bt.clock import WallClock
    wall = WallClock()
    t0 = wall.now()
    row = {"profile": profile, "seed": seed, "level": level}
    try:
        with LockstepGame(options(profile, seed, level)) as game:
            ledger = Ledger(game)
            result = game.run()
            row.update(ledger.numbers())
            row.update(points=result.status.points.get("CYAN", 0), finished=result.finished)
    except Exception as exc:
        row.update(error=f"{type(exc).__name__}: {exc}", trace=traceback.format_exc())
    row["wall"] = round(wall.now() - t0, 1)
    return row


def work(profiles, seeds, levels) -> list[tuple[str, int, str]]:
    """The aim's games first: per seed clean and 20 %, then the other levels, rcll2016 before rcll2025."""
    out = []
    for profile in profiles:
        first = [lv for lv in ("clean", "20") if lv in levels]
        rest = [lv for lv in levels if lv not in first]
        if profile != "rcll2016":
            rest = []
        out += [(profile, s, lv) for s in seeds for lv in first]
        out += [(profile, s, lv) for lv in rest for s in seeds]
    return out


def render(rows: list[dict], commit: str = "") -> str:
    lines = [f"network faults: {DELAY:g} s delay, {JITTER:g} s jitter on every robot's team-server link"
             + (f"; commit {commit}" if commit else "")]
    clean = {(r["profile"], r["seed"]): r.get("points") for r in rows if r["level"] == "clean" and "error" not in r}
    for profile in sorted({r["profile"] for r in rows}):
        lines += ["", f"{profile}:",
                  f"{'network':10} {'games':>5} {'crashed':>7} {'mean pts':>8} {'min % of clean':>14} "
                  f"{'>=80 %':>7} {'task msgs rep.':>14} {'results rep.':>12} {'dropped':>7} {'lost':>5} "
                  f"{'done twice':>10}"]
        for level in LEVELS:
            rs = [r for r in rows if r["profile"] == profile and r["level"] == level]
            if not rs:
                continue
            ok = [r for r in rs if "error" not in r]
            shares = [r["points"] / clean[(profile, r["seed"])] for r in ok
                      if level != "clean" and clean.get((profile, r["seed"]))]
            name = "clean" if level == "clean" else f"loss {level} %"
            lines.append(
                f"{name:10} {len(rs):5d} {len(rs) - len(ok):7d} {fmt(mean(r['points'] for r in ok)):>8} "
                f"{fmt(100 * min(shares) if shares else None, '.0f'):>14} "
                f"{(f'{sum(s >= 0.8 for s in shares)}/{len(shares)}' if shares else '-'):>7} "
                f"{sum(r.get('task_msgs_repeated', 0) for r in ok):14d} "
                f"{sum(r.get('results_repeated', 0) for r in ok):12d} {sum(r.get('robots_dropped', 0) for r in ok):7d} "
                f"{sum(r.get('lost', 0) for r in ok):5d} {sum(r.get('done_twice', 0) for r in ok):10d}")
        lines += ["", f"{'seed':>4} " + " ".join(f"{lv:>8}" for lv in LEVELS) + "   (points per game)"]
        for seed in sorted({r["seed"] for r in rows if r["profile"] == profile}):
            cells = []
            for level in LEVELS:
                r = next((x for x in rows if x["profile"] == profile and x["seed"] == seed and x["level"] == level),
                         None)
                cells.append("" if r is None else ("crash" if "error" in r else str(r["points"])))
            lines.append(f"{seed:4d} " + " ".join(f"{c:>8}" for c in cells))
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10, help="seeds 1..N (default 10)")
    ap.add_argument("--profiles", default="rcll2016,rcll2025")
    ap.add_argument("--levels", default="clean,0,10,20", help="of clean, 0, 10, 20 (default all)")
    ap.add_argument("--jobs", type=int, default=2, help="games in parallel (default 2)")
    ap.add_argument("--json", type=Path, help="append every game's numbers here (JSON lines)")
    ap.add_argument("--render", type=Path, metavar="FILE", help="only print the tables of a --json file")
    args = ap.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    if args.render:
        rows = [json.loads(x) for x in args.render.read_text().splitlines() if x.strip()]
        print(render(rows, rows[0].get("commit", "") if rows else ""))
        return 0
    levels = [lv.strip() for lv in args.levels.split(",")]
    if not set(levels) <= set(LEVELS):
        ap.error(f"--levels: of {', '.join(LEVELS)}")
    items = work([p.strip() for p in args.profiles.split(",")], range(1, args.seeds + 1), levels)
    rows = []
    t0 = time.perf_counter()
    ctx = mp.get_context("spawn")
    with ctx.Pool(args.jobs, maxtasksperchild=2) as pool:
        for row in pool.imap_unordered(play, items):
            row["commit"] = commit
            rows.append(row)
            if args.json:
                with args.json.open("a") as f:
                    f.write(json.dumps(row, default=str) + "\n")
            what = row.get("error") or (f"{row['points']} pts, {row['task_msgs_repeated']} task msgs repeated, "
                                        f"{row['lost']} lost, {row['done_twice']} done twice")
            print(f"  [{time.perf_counter() - t0:6.0f} s] {row['profile']} seed {row['seed']:2d} "
                  f"{row['level']:>5}: {what}", file=sys.stderr, flush=True)
    print(render(rows, commit))
    return 0 if all("error" not in r for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
