"""Estimating a plan: durations, points, and a list-scheduling simulation.

The simulation runs the plan's steps on the robots the way the dispatcher
will: a step is ready when its predecessors are done and its stations are
free (or locked by its own product); each robot takes the ready step it can
start earliest (travel at :attr:`Durations.speed`, carry steps only by the
robot holding the workpiece), and every finished step earns the points the
rules give for it.  Times are production game seconds.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from rll_bt.rules import MPS_TIMES, Profile

from ..knowledge import model as M


@dataclass(frozen=True)
class Durations:
    """Estimated times in seconds; ``speed`` in m/s (driving, with turns).  The machines'
    are the real machines' (:data:`rll_bt.rules.MPS_TIMES`: workpiece on the input to
    product at the output)."""

    speed: float = 0.5
    pickup: float = 15.0
    put: float = 12.0
    shelf: float = 20.0
    bs: float = MPS_TIMES.base              # BS: dispensing and the belt, 3.8 s
    rs: float = MPS_TIMES.ring              # ring mounting, 21.5 s
    cs: float = MPS_TIMES.cap               # cap retrieve / mount, 21.7 s
    ds: float = max(MPS_TIMES.delivery_slots)
    ss: float = MPS_TIMES.retrieve          # storage station retrieve (a store: less)
    discard: float = 5.0

    def handling(self, kind: str) -> float:
        return {M.GET_WORKPIECE: self.pickup, M.RETRIEVE_CAP: self.shelf + self.put,
                M.DISCARD: self.discard}.get(kind, self.put)

    def processing(self, kind: str, machine: str | None, side: str | None = None) -> float:
        """Machine time after the step before its result can be taken."""
        if kind == M.MOUNT_RING:
            return self.rs
        if kind in (M.MOUNT_CAP, M.RETRIEVE_CAP):
            return self.cs
        if kind == M.DELIVER:
            return self.ds
        if kind == M.GET_WORKPIECE and machine and machine.endswith("BS"):
            return self.bs
        if kind in (M.GET_WORKPIECE, M.PUT_WORKPIECE) and machine and machine.endswith("SS"):
            return self.ss
        return 0.0


def step_points(profile: Profile, kind: str, params: dict, order: M.Order | None,
                finish: float) -> int:
    """Points the rules give when a step of ``kind`` finishes at game time ``finish``."""
    s = profile.scoring
    if kind == M.PUT_WORKPIECE and params.get("side") == M.SLIDE:
        return s.additional_base
    if kind == M.PUT_WORKPIECE and params.get("store"):
        return s.ss_store                         # 2025: -5 for storing
    if kind == M.GET_WORKPIECE and str(params.get("machine", "")).endswith("SS"):
        return s.ss_retrieve                      # 2025: -5 for retrieving
    if kind == M.MOUNT_RING:
        pts = profile.ring_points(int(params.get("cost", 0)))
        if order is not None and params.get("ring_color") == order.rings[-1]:
            pts += s.precap_by_complexity[order.complexity]
        return pts
    if kind == M.MOUNT_CAP:
        return s.cap_mounted
    if kind == M.RETRIEVE_CAP:
        return s.cap_retrieved
    if kind == M.DELIVER and order is not None:
        pts = profile.delivery_points(order.complexity, max(finish, order.begin), order.end,
                                      order.begin)
        if order.competitive:
            pts += s.competitive_first
        return pts
    return 0


@dataclass
class SimTask:
    """A step as the simulation sees it."""

    key: object
    product: str
    kind: str
    machine: str | None
    params: dict
    deps: tuple = ()
    locks: tuple = ()
    releases: tuple = ()
    carry: bool = False
    holder: str | None = None       # robot bound to it (carry steps, running steps)
    not_before: float = 0.0
    order: M.Order | None = None


@dataclass
class SimRobot:
    name: str
    pos: tuple[float, float]
    free_at: float


@dataclass
class SimResult:
    points: int = 0
    finish: dict = field(default_factory=dict)       # task key -> finish time
    product_done: dict = field(default_factory=dict)  # product -> delivery time
    makespan: float = 0.0


def simulate(profile: Profile, tasks: list[SimTask], robots: list[SimRobot],
             positions: dict[str, tuple[float, float]], now: float, horizon: float,
             durations: Durations = Durations(), done: set | None = None,
             owned: dict[str, str] | None = None) -> SimResult:
    """List-schedule ``tasks`` on ``robots`` from game time ``now``; points by ``horizon``.

    ``done``: keys of steps already finished; ``owned``: lock -> product at the start.
    """
    res = SimResult()
    if not robots:
        return res
    done = set(done or ())
    finish: dict = dict.fromkeys(done, now)
    locks: dict[str, str] = dict(owned or {})
    holder_of: dict = {}            # carry task key -> robot that made the pickup
    holding: dict[str, object] = {}  # robot -> carry task it must do next
    busy: dict[str, float] = {}      # lock -> when the step using it ends
    pending = [t for t in tasks if t.key not in done]
    rb = {r.name: SimRobot(r.name, r.pos, max(r.free_at, now)) for r in robots}
    for t in pending:
        if t.carry and t.holder and all(d in finish for d in t.deps):
            holding[t.holder] = t.key   # the robot already carries this workpiece
    while pending:
        best = None
        for t in pending:
            if any(d not in finish for d in t.deps):
                continue
            if any(locks.get(lk, t.product) != t.product for lk in t.locks):
                continue
            ready = max([now, t.not_before] + [finish[d] for d in t.deps]
                        + [busy.get(lk, now) for lk in t.locks])
            if t.carry or t.holder:
                cands = [t.holder or holder_of.get(t.key)]
            else:
                cands = [n for n in rb if n not in holding]
            pos = positions.get(t.machine) if t.machine else None
            for name in cands:
                r = rb.get(name) if name else None
                if r is None:
                    continue
                travel = 0.0 if pos is None else math.dist(r.pos, pos) / durations.speed
                start = max(r.free_at + travel, ready)
                if best is None or start < best[0]:
                    best = (start, t, r, pos)
        if best is None:
            break                       # the rest is blocked (a lock never released)
        start, t, r, pos = best
        pending.remove(t)
        if t.kind == M.GET_WORKPIECE:
            end = start + durations.processing(t.kind, t.machine, None) + durations.pickup
            finish[t.key] = end
            for other in pending:
                if other.carry and t.key in other.deps:
                    holder_of[other.key] = r.name
                    holding[r.name] = other.key
        else:
            end = start + durations.handling(t.kind)
            finish[t.key] = end + durations.processing(t.kind, t.machine, None)
            if holding.get(r.name) == t.key:
                del holding[r.name]
        r.free_at, r.pos = end, pos or r.pos
        for lk in t.locks:
            locks[lk] = t.product
            busy[lk] = end
        for lk in t.releases:
            locks.pop(lk, None)
        if finish[t.key] <= horizon:
            res.points += step_points(profile, t.kind, t.params, t.order, finish[t.key])
            if t.kind == M.DELIVER:
                res.product_done[t.product] = finish[t.key]
        res.makespan = max(res.makespan, finish[t.key])
    res.finish = finish
    return res
