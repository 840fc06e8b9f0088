"""What a game did over time, sampled on the simulation clock.

:class:`Recorder` keeps, per sample (every ``period`` s): the phase, game
time and our score; each robot's true pose (paths); station states (on
change); and, from the team server, when every own station became
correctly known: every property its exploration report scores (zone and
light code in 2016, zone and rotation from 2017 on) known for sure and
right.  Everything is plain data for the report
and the plots; times are simulation seconds.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Recording:
    team: str = "CYAN"
    samples: list[dict] = field(default_factory=list)          # t, phase, game_time, points
    paths: dict[int, list[tuple[float, float, float]]] = field(default_factory=dict)   # robot -> (t, x, y)
    stations: dict[str, list[tuple[float, str]]] = field(default_factory=dict)         # name -> (t, state)
    phases: list[tuple[float, str]] = field(default_factory=list)                       # (t, phase entered)
    events: list[dict] = field(default_factory=list)            # faults and notes: t, what, ...
    tasks: dict[int, list[dict]] = field(default_factory=dict)  # robot -> {kind, id, start, end, outcome}
    known_all_at: float | None = None       # sim time every own station was correctly known
    known_all_game_time: float | None = None  # the same in game seconds of exploration
    exploration_started: float | None = None

    def phase_start(self, phase: str) -> float | None:
        for t, p in self.phases:
            if p == phase:
                return t
        return None


class Recorder:
    """Samples a :class:`~rll_bt.contracts.World` (robot poses, on its clock),
    a :class:`~rll_bt.contracts.RefboxView` (the game) and a team server's
    ``snapshot()``."""

    def __init__(self, world, refbox, team: str, robots: list[int], period: float = 1.0, snapshot=None):
        self.world, self.refbox = world, refbox
        self.team = team
        self.robots = robots
        self.period = period
        self.snapshot = snapshot          # () -> team server snapshot dict, or None
        self.rec = Recording(team=team)
        #: ``fn(kind, data)`` for every "sample", "task" interval change and "event" (recordings, live views)
        self.listeners: list = []
        props = ("zone", "light") if world.profile.exploration_reports == "type+zone" else ("zone", "orientation")
        self.truth = {n: s.reported(props) for n, s in refbox.stations().items() if s.team == team}
        self._next = -1e9

    def task(self, robot: int, kind: str | None, task_id: int | None = None,
             outcome: str | None = None) -> None:
        """What ``robot`` is doing now (``kind`` None: nothing); records an interval per task."""
        now = round(self.world.clock.now(), 3)
        runs = self.rec.tasks.setdefault(robot, [])
        cur = runs[-1] if runs and runs[-1]["end"] is None else None
        if cur is not None and (cur["id"], cur["kind"]) == (task_id, kind):
            return
        if cur is not None:
            cur["end"] = now
            cur["outcome"] = outcome or "CANCELLED"
            self._emit("task", {"robot": robot, "index": len(runs) - 1, **cur})
        elif outcome is not None and runs and runs[-1]["outcome"] is None:
            runs[-1]["outcome"] = outcome
            self._emit("task", {"robot": robot, "index": len(runs) - 1, **runs[-1]})
        if kind is not None:
            runs.append({"kind": kind, "id": task_id, "start": now, "end": None, "outcome": None})
            self._emit("task", {"robot": robot, "index": len(runs) - 1, **runs[-1]})

    def _emit(self, kind: str, data: dict) -> None:
        for fn in self.listeners:
            fn(kind, data)

    def close_tasks(self) -> None:
        for robot in list(self.rec.tasks):
            self.task(robot, None, outcome="running at the end")

    def note(self, what: str, **data) -> None:
        self.rec.events.append({"t": round(self.world.clock.now(), 3), "what": what, **data})
        self._emit("event", self.rec.events[-1])

    def sample(self, force: bool = False) -> None:
        now = self.world.clock.now()
        if not force and now < self._next:
            return
        self._next = now + self.period
        st = self.refbox.status()
        rec = self.rec
        if not rec.phases or rec.phases[-1][1] != st.phase:
            rec.phases.append((now, st.phase))
        if rec.exploration_started is None and self._exploring(st):
            rec.exploration_started = now - st.game_time
        rec.samples.append({"t": round(now, 3), "phase": st.phase, "game_time": round(st.game_time, 3),
                            "points": st.points.get(self.team, 0)})
        out = {**rec.samples[-1], "now": now, "paths": {}, "stations": {}}
        for n in self.robots:
            p = self.world.robot_pose(self.team, n)
            rec.paths.setdefault(n, []).append((round(now, 2), round(p.x, 3), round(p.y, 3)))
            out["paths"][n] = rec.paths[n][-1]
        for name, s in self.refbox.stations().items():
            hist = rec.stations.setdefault(name, [])
            if not hist or hist[-1][1] != s.state:
                hist.append((round(now, 3), s.state))
                out["stations"][name] = hist[-1]
        if rec.known_all_at is None and self.snapshot is not None and rec.exploration_started is not None:
            snap = self.snapshot()
            known = (snap or {}).get("known", {})
            if all(_matches(known.get(n), truth) for n, truth in self.truth.items()):
                rec.known_all_at = now
                rec.known_all_game_time = now - rec.exploration_started
        if self.listeners:
            self._emit("sample", {**out, "exploration_started": rec.exploration_started,
                                  "known_all_at": rec.known_all_at, "known_all_game_time": rec.known_all_game_time})

    @staticmethod
    def _exploring(st) -> bool:
        return st.phase in ("EXPLORATION", "PRODUCTION") and st.state == "RUNNING"


def _matches(known, truth: dict) -> bool:
    """The team server's sure properties of a machine hold every true value."""
    if not known:
        return False
    return all(p in known and (tuple(known[p]) if p == "light" else known[p]) == v for p, v in truth.items())
