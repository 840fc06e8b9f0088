"""The team-server link in a ``--processes`` game: logged, put on the game's clock, merged.

In lockstep every frame crosses one in-process bus and one tap logs them
all.  With ``--processes`` the team server's TCP link to the agents runs
between two other processes, so the team server logs its side of it
(:class:`LoggedStreamServer`: what it sends to each agent, what it gets
from them), stamped with its wall clock (monotonic seconds, the same
clock in every process of the machine).  At the end the runner maps those
stamps onto the simulation clock (:class:`WallToSim`, pairs it recorded
while stepping the world), merges them with the refbox's lines into one
``messages.jsonl`` in time order (:func:`merge_into`), and reads every
robot's task intervals from them (:func:`task_runs`) as lockstep records
them from its agents.

Lines have the lockstep schema: ``{"t", "channel": "teamserver", "from":
"teamserver" or "R<robot>", "type", "msg"}``; in a game of two teams
each team's as lockstep names them (``teamserver-cyan``, ``C-R1``).
"""
from __future__ import annotations

import bisect
import heapq
import json
import os
from collections.abc import Iterable, Iterator
from pathlib import Path

from rll_bt.comm import StreamServer

CHANNEL = "teamserver"
SERVER = "teamserver"


class LoggedStreamServer(StreamServer):
    """A :class:`~rll_bt.comm.StreamServer` that records every message it
    sends (one line per client it reaches, as the bus carries them) and
    receives into ``log`` (a :class:`~games.msglog.MessageLog`).
    A client is named ``<prefix>R<robot_id>`` after the first message naming its robot;
    the lines say ``channel`` and the server is ``server``."""

    def __init__(self, *args, log, channel: str = CHANNEL, server: str = SERVER, prefix: str = "", **kwargs):
        super().__init__(*args, **kwargs)
        self.log = log
        self.channel, self.server, self.prefix = channel, server, prefix
        self._names: dict[int, str] = {}

    def send(self, msg, to: int | None = None) -> bool:
        targets = self.clients() if to is None else [to]
        sent = False
        for cid in targets:
            if super().send(msg, to=cid):
                sent = True
                self.log.record(self.channel, self.server, msg)
        return sent

    def receive(self):
        items = super().receive()
        for rx in items:
            self.log.record(self.channel, self._name(rx), rx.msg)
        return items

    def _name(self, rx) -> str:
        fields = rx.msg.DESCRIPTOR.fields_by_name
        for f in ("robot_id", "number"):            # rll-bt's messages and AgentTask; BeaconSignal
            if f in fields and rx.msg.HasField(f):
                self._names[rx.source] = f"{self.prefix}R{int(getattr(rx.msg, f))}"
                break
        return self._names.get(rx.source, f"client{rx.source}")

    def _drop(self, cid: int) -> None:
        self._names.pop(cid, None)
        super()._drop(cid)


class WallToSim:
    """Wall-clock seconds -> simulation seconds, from (wall, sim) pairs taken
    as the world stepped.  The world may fall behind the wall clock (it steps
    at most 0.1 s at a time); the pairs are kept where that gap changed, and
    times between them are interpolated, before the first or after the last
    carried on at the wall clock's rate."""

    def __init__(self, tolerance: float = 1e-3):
        self.tolerance = tolerance
        self._wall: list[float] = []
        self._sim: list[float] = []
        self._pending: tuple[float, float] | None = None

    def add(self, wall: float, sim: float) -> None:
        if self._wall and wall <= self._wall[-1]:
            return
        if self._wall and abs((wall - sim) - (self._wall[-1] - self._sim[-1])) <= self.tolerance:
            self._pending = (wall, sim)         # same gap: only needed as the end of this stretch
            return
        if self._pending is not None:
            self._append(*self._pending)
        self._pending = None
        self._append(wall, sim)

    def _append(self, wall: float, sim: float) -> None:
        self._wall.append(wall)
        self._sim.append(sim)

    def __len__(self) -> int:
        return len(self._wall) + (self._pending is not None)

    def __call__(self, wall: float) -> float:
        walls, sims = self._wall, self._sim
        if self._pending is not None:
            walls, sims = walls + [self._pending[0]], sims + [self._pending[1]]
        if not walls:
            raise ValueError("no (wall, sim) pairs yet")
        i = bisect.bisect_right(walls, wall)
        if i == 0:
            return sims[0] + (wall - walls[0])
        if i == len(walls):
            return sims[-1] + (wall - walls[-1])
        w0, w1, s0, s1 = walls[i - 1], walls[i], sims[i - 1], sims[i]
        return s0 + (s1 - s0) * (wall - w0) / (w1 - w0)


def read_lines(path: str | Path, to_sim=None) -> list[dict]:
    """The JSON lines of ``path`` (a line cut off by a killed writer is left out);
    with ``to_sim`` every ``t`` is mapped through it."""
    out = []
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        return out
    for raw in text.splitlines():
        try:
            entry = json.loads(raw)
        except ValueError:
            continue
        if to_sim is not None:
            entry["t"] = round(to_sim(entry["t"]), 4)
        out.append(entry)
    return out


def merge_into(path: str | Path, *streams: Iterable[dict], shift: float = 0.0) -> int:
    """Add ``streams`` (each in time order) to the JSON-lines log at ``path``
    (in time order), keeping the lines in time order and making every ``t``
    ``shift`` seconds earlier; returns the lines written."""
    path = Path(path)
    tmp = path.with_name(path.name + ".merging")
    n = 0
    with open(tmp, "w", encoding="utf-8") as fh:
        for entry in heapq.merge(_iter_file(path), *streams, key=lambda e: e["t"]):
            if shift:
                entry = {**entry, "t": round(entry["t"] - shift, 4)}
            fh.write(json.dumps(entry, separators=(",", ":")) + "\n")
            n += 1
    os.replace(tmp, path)
    return n


def _iter_file(path: Path) -> Iterator[dict]:
    if not path.exists():
        return
    with open(path, encoding="utf-8") as fh:
        for raw in fh:
            if raw.strip():
                yield json.loads(raw)


def _league_kind(m: dict) -> str | None:
    """The tree kind of a task that came without rll-bt's TaskDetail."""
    from rll_bt.agenttask.read import BODY_KINDS
    body = next((b for b in BODY_KINDS if b in m), None)
    return BODY_KINDS[body][0] if body is not None else None


def task_runs(lines: Iterable[dict], end: float | None = None, *, channel: str = CHANNEL,
              server: str = SERVER) -> dict[int, list[dict]]:
    """Each robot's task intervals from team-server link lines in time order:
    ``{robot: [{"kind", "id", "start", "end", "outcome"}]}``.  An AgentTask
    the server sends a robot starts a run (its kind from the TaskDetail just
    before it; a repeat of the open task changes nothing, a different one
    ends the open run as CANCELLED; a cancel or pause request starts
    nothing); the robot's AgentTask echoed with ``successful`` / ``canceled``
    ends it (SUCCEEDED, FAILED or CANCELLED); a task sent to run after the open one
    (its TaskDetail's ``after``) starts when that one succeeded.  Runs still open are closed at
    ``end`` ("running at the end"), or left with ``end`` None.  ``channel`` and
    ``server``: the team's link and its server as the lines name them."""
    runs: dict[int, list[dict]] = {}
    kinds: dict[tuple[int, int], str] = {}
    afters: dict[tuple[int, int], int] = {}
    queued: dict[int, dict] = {}         # robot -> the run sent to start once its open one succeeds
    for e in lines:
        if e.get("channel") != channel or e.get("type") not in ("AgentTask", "TaskDetail"):
            continue
        m = e["msg"]
        robot, tid, t = int(m["robot_id"]), int(m["task_id"]), e["t"]
        if e["type"] == "TaskDetail":
            if m.get("kind"):
                kinds[(robot, tid)] = m["kind"]
            if m.get("after") is not None:
                afters[(robot, tid)] = int(m["after"])
            continue
        mine = runs.setdefault(robot, [])
        cur = mine[-1] if mine and mine[-1]["end"] is None else None
        if e["from"] == server:
            after = afters.pop((robot, tid), None)
            if m.get("cancel_task") or "pause_task" in m or cur is not None and cur["id"] == tid:
                continue
            run = {"kind": kinds.pop((robot, tid), None) or _league_kind(m), "id": tid, "start": t,
                   "end": None, "outcome": None}
            if cur is not None and after == cur["id"]:
                queued[robot] = run                 # runs once the open one succeeded (TaskDetail after)
                continue
            if cur is not None:
                cur["end"], cur["outcome"] = t, "CANCELLED"
            mine.append(run)
        elif ("successful" in m or "canceled" in m) and cur is not None and cur["id"] == tid:
            outcome = "CANCELLED" if m.get("canceled") else "SUCCEEDED" if m.get("successful") else "FAILED"
            cur["end"], cur["outcome"] = t, outcome
            nxt = queued.pop(robot, None)
            if nxt is not None and outcome == "SUCCEEDED":
                mine.append({**nxt, "start": t})
    if end is not None:
        for mine in runs.values():
            for run in mine:
                if run["end"] is None:
                    run["end"], run["outcome"] = max(end, run["start"]), "running at the end"
    return {r: v for r, v in runs.items() if v}
