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


def collisions_of(log, team: str) -> list[list]:
    """The collisions of ``team``'s robots, each as [game time, robot ("CYAN/2"), what it hit],
    kept in report.json (a process game is played once: what was hit and when is the evidence)."""
    return [[round(float(t), 2), robot, what] for t, robot, what in log if robot.split("/")[0] == team]


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


def _other_team_collisions(log) -> int:
    """Collisions of a robot with a robot of the other team."""
    return sum(1 for _t, robot, what in log
               if what.startswith("robot ") and what[len("robot "):].split("/")[0] != robot.split("/")[0])


def _own_team_collisions(log) -> dict[str, int]:
    """Collisions of a robot with a robot of its own team, per team (teams without any left out)."""
    out: dict[str, int] = {}
    for _t, robot, what in log:
        team = robot.split("/")[0]
        if what.startswith("robot ") and what[len("robot "):].split("/")[0] == team:
            out[team] = out.get(team, 0) + 1
    return out


def summarise(result, options: GameOptions, team: str | None = None, wall_time: float | None = None) -> dict:
    """The report of ``team`` (default: the first team of the game); a game of
    two teams adds ``teams`` (each colour's report, without the game-wide
    fields) and ``match`` (the score, who won, collisions between the teams,
    what each robot's laser saw of the other team)."""
    team = team or next(iter(getattr(result, "recordings", None) or {}), None) or result.recording.team
    out = _summarise(result, options, team, wall_time)
    recordings = getattr(result, "recordings", None) or {}
    if len(recordings) > 1:
        out["teams"] = {c: _team_part(_summarise(result, options, c, wall_time)) for c in recordings}
        out["match"] = match(result)
    return out


TEAM_FIELDS = ("team", "config", "robots", "strategy", "baseline", "points", "exploration", "orders_delivered",
               "deliveries", "robot_stats", "team_server_restarts", "awards", "events")


def _team_part(summary: dict) -> dict:
    return {k: summary[k] for k in TEAM_FIELDS if k in summary}


def match(result) -> dict:
    """Both teams' scores, the winner ("CYAN", "MAGENTA" or None for a draw),
    collisions between the teams and within each team, and the laser
    sightings of the other team."""
    points = {c: int(result.status.points.get(c, 0)) for c in result.recordings}
    cyan, magenta = points.get("CYAN", 0), points.get("MAGENTA", 0)
    winner = None if cyan == magenta else ("CYAN" if cyan > magenta else "MAGENTA")
    seen = {robot: sum(n for other, n in saw.items() if other.split("/")[0] != robot.split("/")[0])
            for robot, saw in (result.sightings or {}).items()}
    return {"points": points, "labels": dict(result.labels), "winner": winner,
            "collisions_between_teams": _other_team_collisions(result.collision_log),
            "collisions_within_teams": {c: _own_team_collisions(result.collision_log).get(c, 0)
                                        for c in result.recordings},
            "other_team_in_laser_scans": {r: n for r, n in sorted(seen.items()) if n}}


def _summarise(result, options: GameOptions, team: str, wall_time: float | None) -> dict:
    recordings = getattr(result, "recordings", None) or {}
    rec = recordings.get(team, result.recording)
    snapshot = (getattr(result, "snapshots", None) or {}).get(team, result.snapshot)
    teams = options.lineup()
    me = teams.get(team)
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
        "profile": options.profile, "seed": options.seed,
        "strategy": me.strategy if me is not None else options.strategy,
        "perception": "camera (emulated hardware)" if options.hardware == "emulated" else options.perception,
        "hardware": options.hardware, "robots": me.robots if me is not None else options.robots, "team": team,
        "config": (getattr(result, "labels", None) or {}).get(team) or (me.label if me is not None else None),
        "baseline": me.baseline if me is not None else options.baseline,
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
        "collisions_between_teams": _other_team_collisions(result.collision_log),
        "collision_log": collisions_of(result.collision_log, team),
        "messages": result.messages,
        "team_server_restarts": snapshot.get("restarts", 0),
        "hardware_stats": snapshot.get("hardware", {}),
        **({"world_lag": snapshot["world_lag"]} if snapshot.get("world_lag") else {}),
        **_tally(result, team),
        "awards": [asdict(a) for a in result.awards if a.team == team],
        "events": rec.events,
    }


def table(summary: dict) -> str:
    """The report for a person: one team's, or both teams' side by side."""
    if summary.get("teams"):
        return match_table(summary)
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
    lag = s.get("world_lag")
    if lag:
        lines += ["", f"world behind the wall clock: at most {lag['longest_s']:.2f} s; more than "
                  f"{lag['stale_above_s']:g} s (no laser casts, no camera frames) for {lag['stale_s']:.1f} s "
                  f"in {lag['stale_spells']} spells"]
    return "\n".join(lines)


def match_table(summary: dict) -> str:
    """Both teams of a game side by side, then the match and every robot."""
    s, teams, m = summary, summary["teams"], summary["match"]
    colors = list(teams)
    head = {c: f"{c} {teams[c]['config'] or ''}".strip() for c in colors}
    width = max(18, *(len(h) + 2 for h in head.values()))

    def row(label: str, values) -> str:
        return f"{label:22}" + "".join(f"{v:>{width}}" for v in values)
    win = m["winner"]
    result = (f"{head[win]} won {m['points'][win]} : {min(m['points'].values())}" if win
              else f"a draw at {m['points'][colors[0]]}")
    lines = [
        f"{s['profile']} seed {s['seed']}, perception {s['perception']}: "
        + " against ".join(f"{c.lower()} {teams[c]['config']} ({teams[c]['robots']} robots, strategy "
                           f"{teams[c]['strategy']})" for c in colors),
        f"game {'finished' if s['finished'] else 'NOT finished'} in phase {s['phase']} after "
        f"{s['sim_time']:.0f} s simulated" + (f", {s['wall_time']:.0f} s wall" if s.get("wall_time") else "")
        + (f" (SETUP shortened to {s['phase_lengths']['SETUP']:.0f} s)" if s["setup_shortened"] else ""),
        "",
        row("", [head[c] for c in colors]),
        row("exploration points", [f"{teams[c]['exploration']['points']} / {teams[c]['exploration']['max_points']}"
                                   for c in colors]),
        row("production points", [teams[c]["points"]["production"] for c in colors]),
        row("total score", [teams[c]["points"]["total"] for c in colors]),
        row("orders delivered", [teams[c]["orders_delivered"] for c in colors]),
        "",
        f"{result}; collisions between the teams {m['collisions_between_teams']}, all collisions "
        f"{s['collisions']} (" + ", ".join(f"{k} {v}" for k, v in sorted(s.get("collisions_by_kind", {}).items()))
        + ")",
        "",
        f"{'robot':8} {'busy s':>8} {'busy %':>7} {'tasks':>6} {'failed':>7} {'driven m':>9} {'other team seen':>16}",
    ]
    seen = m.get("other_team_in_laser_scans", {})
    for c in colors:
        for n, r in teams[c]["robot_stats"].items():
            lines.append(f"{c[0]}-R{n:<5} {r['busy_time']:8.0f} {100 * r['busy_share']:6.0f}% {r['tasks']:6d} "
                         f"{r['failed']:7d} {r['distance']:9.1f} {seen.get(f'{c}/{n}', 0):>9d} scans")
    return "\n".join(lines)


def write_json(summary: dict, path: str | Path) -> None:
    Path(path).write_text(json.dumps(summary, indent=2, default=str) + "\n", encoding="utf-8")
