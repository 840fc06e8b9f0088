"""The result of a game as data (``report.json``) and as a table.

:func:`summarise` turns a :class:`~games.lockstep.GameResult` into a
plain dict: points by phase, exploration (points, the maximum, game seconds
until every exploration point was scored, i.e. every own station correctly
reported, and until the team server was sure of every station), orders
delivered, and per
robot the busy time (s a task tree was running), tasks, failures and
distance driven (m, ground truth); the team's stations that went BROKEN,
by cause, and the referee calls (a dropped workpiece, an obstruction, a
machine prepared and never fed) with the rulebook's penalties, which the
refbox leaves to a human referee and the score does not include.  :func:`table` renders it for a person.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path

from rll_bt.contracts import Tally

from .options import GameOptions, max_exploration_points

SCORED = ("in-time", "late")


def _distance(path) -> float:
    return sum(math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(path, path[1:]))


def _collision_kinds(log) -> dict[str, int]:
    """Collision events by what was hit: "robot", "wall" or "station"."""
    out: dict[str, int] = {}
    for _t, _robot, what in log:
        kind = "robot" if what.startswith("robot") else ("wall" if what == "wall" else "station")
        out[kind] = out.get(kind, 0) + 1
    return out


def _exploration(award) -> bool:
    """An exploration award: in its own phase, or a report judged inside PRODUCTION (2025)."""
    if award.phase == "EXPLORATION":
        return True
    return award.order is None and any(w in award.reason for w in (" zone ", " type ", " rotation "))


def exploration_points(awards, team: str) -> int:
    """The exploration points ``team`` holds among ``awards``."""
    return sum(a.points for a in awards if a.team == team and _exploration(a))


def all_points_after(awards, team: str, want: int) -> float | None:
    """Game seconds (of exploration) when ``team``'s exploration points first
    reached ``want``: every own station reported right; None if never."""
    got = 0
    for a in sorted((a for a in awards if a.team == team and _exploration(a)), key=lambda a: a.game_time):
        got += a.points
        if got >= want:
            return round(a.game_time, 2)
    return None


def _tally(result, team: str) -> dict:
    """The stations of ``team`` that went BROKEN by cause, and the referee calls (what the
    refbox leaves to a human referee: reported with the rulebook's penalty, not scored)."""
    t = getattr(result, "tally", {}).get(team) or Tally()
    return {"stations_broken": {"total": t.broken_total, "by_cause": dict(t.broken)},
            "referee": {"calls": {k: dict(v) for k, v in t.referee.items()},
                        "penalty": t.referee_penalty}}


def summarise(result, options: GameOptions, team: str = "CYAN", wall_time: float | None = None) -> dict:
    rec = result.recording
    prof = options.rules
    by_phase: dict[str, int] = {}
    for a in result.awards:
        if a.team == team:
            by_phase[a.phase] = by_phase.get(a.phase, 0) + a.points
    explore_pts = exploration_points(result.awards, team)
    production_pts = sum(a.points for a in result.awards if a.team == team and a.phase == "PRODUCTION"
                         and not _exploration(a))
    ours = [d for d in result.deliveries if d.team == team]
    robots = {}
    end = result.sim_time
    for n in sorted(set(rec.paths) | set(rec.tasks)):
        runs = rec.tasks.get(n, [])
        busy = sum((r["end"] if r["end"] is not None else end) - r["start"] for r in runs)
        failed = sum(1 for r in runs if r.get("outcome") == "FAILED")
        robots[str(n)] = {"busy_time": round(busy, 1),
                          "busy_share": round(busy / end, 3) if end > 0 else 0.0,
                          "tasks": len(runs), "failed": failed,
                          "distance": round(_distance(rec.paths.get(n, [])), 1)}
    lengths = options.phase_lengths()
    rules_setup = prof.phases.setup
    return {
        "profile": options.profile, "seed": options.seed, "strategy": options.strategy,
        "perception": "camera (emulated hardware)" if options.hardware == "emulated" else options.perception,
        "hardware": options.hardware, "robots": options.robots, "team": team,
        "baseline": options.baseline,
        "finished": bool(result.finished), "phase": result.status.phase,
        "sim_time": round(result.sim_time, 2),
        "wall_time": round(wall_time, 2) if wall_time is not None else None,
        "phase_lengths": lengths,
        "setup_shortened": lengths["SETUP"] < rules_setup,
        "points": {"total": result.status.points.get(team, 0), "by_phase": by_phase,
                   "exploration": explore_pts, "production": production_pts},
        "exploration": {"points": explore_pts, "max_points": max_exploration_points(prof),
                        "wrong": sum(1 for a in result.awards if a.team == team and _exploration(a) and a.points < 0),
                        "all_points_after": all_points_after(result.awards, team, max_exploration_points(prof)),
                        "sure_all_after": (round(rec.known_all_game_time, 2)
                                           if rec.known_all_game_time is not None else None)},
        "orders_delivered": sum(1 for d in ours if d.how in SCORED),
        "deliveries": [asdict(d) for d in ours],
        "robot_stats": robots,
        "collisions": result.collisions,
        "collisions_by_kind": _collision_kinds(result.collision_log),
        "messages": result.messages,
        "team_server_restarts": result.snapshot.get("restarts", 0),
        "hardware_stats": result.snapshot.get("hardware", {}),
        **_tally(result, team),
        "awards": [asdict(a) for a in result.awards if a.team == team],
        "events": rec.events,
    }


def table(summary: dict) -> str:
    s = summary
    ex = s["exploration"]
    known = (f"all scored after {ex['all_points_after']:.0f} s" if ex["all_points_after"] is not None
             else "not all scored")
    known += (f"; the team server sure of every station after {ex['sure_all_after']:.0f} s"
              if ex["sure_all_after"] is not None else "")
    lines = [
        f"{s['profile']} seed {s['seed']}, {s['robots']} robots, strategy {s['strategy']}, "
        f"perception {s['perception']}" + (" (baseline production)" if s.get("baseline") else ""),
        f"game {'finished' if s['finished'] else 'NOT finished'} in phase {s['phase']} after "
        f"{s['sim_time']:.0f} s simulated" + (f", {s['wall_time']:.0f} s wall" if s.get("wall_time") else "")
        + (f" (SETUP shortened to {s['phase_lengths']['SETUP']:.0f} s)" if s["setup_shortened"] else ""),
        "",
        f"{'exploration points':22} {ex['points']:5d} / {ex['max_points']}   ({known})",
        f"{'production points':22} {s['points']['production']:5d}",
        f"{'total score':22} {s['points']['total']:5d}",
        f"{'orders delivered':22} {s['orders_delivered']:5d}",
        f"{'stations broken':22} {s.get('stations_broken', {}).get('total', 0):5d}   "
        + ", ".join(f"{k} {v}" for k, v in s.get("stations_broken", {}).get("by_cause", {}).items()),
        f"{'referee calls':22} {sum(c['count'] for c in s.get('referee', {}).get('calls', {}).values()):5d}   "
        + ", ".join(f"{k} {c['count']} ({c['penalty']:+d})"
                    for k, c in s.get("referee", {}).get("calls", {}).items()),
        f"{'collisions':22} {s['collisions']:5d}   "
        + ", ".join(f"{k} {v}" for k, v in sorted(s.get("collisions_by_kind", {}).items())),
        "",
        f"{'robot':6} {'busy s':>8} {'busy %':>7} {'tasks':>6} {'failed':>7} {'driven m':>9}",
    ]
    for n, r in s["robot_stats"].items():
        lines.append(f"R{n:<5} {r['busy_time']:8.0f} {100 * r['busy_share']:6.0f}% {r['tasks']:6d} "
                     f"{r['failed']:7d} {r['distance']:9.1f}")
    hw = s.get("hardware_stats") or {}
    if hw:
        lines += ["", f"{'device':8} {'serial polls/s':>14} {'scans/s':>8} {'frames/s':>9} {'watchdog stops':>15}"]
        for name, h in sorted(hw.items()):
            lines.append(f"{name:8} {h['serial_polls_per_s']:14.1f} {h['scans_per_s']:8.2f} {h['frames_per_s']:9.2f} "
                         f"{h['watchdog_motion_stops']:15d}")
    return "\n".join(lines)


def write_json(summary: dict, path: str | Path) -> None:
    Path(path).write_text(json.dumps(summary, indent=2, default=str) + "\n", encoding="utf-8")
