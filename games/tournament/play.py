"""One game of a tournament, as a worker plays it: plain data in, plain data out.

:func:`play_match` takes a :class:`~.schedule.Match` as a dict and returns
the game's row: both scores, the winner, collisions between the teams,
within each team and with stations and walls, and where and how long it
ran.  It plays a lockstep game (deterministic for its seed: the same row
on any machine, whatever executor sent it there); a game
that raises returns a row with ``error`` instead, so one bad game does not
lose a long tournament.
"""
from __future__ import annotations

import os
import socket
import time
import traceback

#: the fields of a row that depend on the game only (not on where or how fast it ran)
GAME_FIELDS = ("key", "cyan", "magenta", "seed", "points", "winner", "finished", "sim_time",
               "collisions_between_teams", "collisions_within_teams", "collisions_with", "deliveries",
               "exploration", "error")


def options_for(match):
    """The :class:`~games.options.GameOptions` of a :class:`~.schedule.Match`."""
    from ..options import GameOptions
    s = match.settings
    return GameOptions(seed=match.seed, cyan=match.cyan, magenta=match.magenta, profile=s["profile"],
                       setup=s["setup"], exploration=s["exploration"], production=s["production"],
                       overtime=s.get("overtime"),
                       robots=s["robots"], strategy=s["strategy"])


def play_match(data: dict) -> dict:
    """The row of the game ``data`` (a :meth:`Match.to_dict`)."""
    from .. import finish
    from ..lockstep import LockstepGame
    from .schedule import Match
    match = Match.from_dict(data)
    row = {"key": match.key, "cyan": match.cyan, "magenta": match.magenta, "seed": match.seed,
           "host": socket.gethostname(), "pid": os.getpid()}
    t0 = time.monotonic()
    try:
        options = options_for(match)
        with LockstepGame(options) as game:
            result = game.run()
            summary = finish(result, options, time.monotonic() - t0)
    except Exception as exc:
        return {**row, "error": f"{type(exc).__name__}: {exc}", "trace": traceback.format_exc(),
                "wall_time": round(time.monotonic() - t0, 1), "ended": round(time.time(), 1)}
    m = summary["match"]
    points = {"cyan": m["points"].get("CYAN", 0), "magenta": m["points"].get("MAGENTA", 0)}
    winner = None if m["winner"] is None else (match.cyan if m["winner"] == "CYAN" else match.magenta)
    teams = summary["teams"]
    kinds = summary.get("collisions_by_kind", {})
    return {**row, "points": points, "winner": winner, "finished": summary["finished"],
            "sim_time": summary["sim_time"], "collisions_between_teams": m["collisions_between_teams"],
            "collisions_within_teams": {c.lower(): n for c, n in m["collisions_within_teams"].items()},
            "collisions_with": {"station": kinds.get("station", 0), "wall": kinds.get("wall", 0)},
            "deliveries": {c.lower(): teams[c]["orders_delivered"] for c in ("CYAN", "MAGENTA")},
            "exploration": {c.lower(): teams[c]["points"]["exploration"] for c in ("CYAN", "MAGENTA")},
            "error": None, "wall_time": round(time.monotonic() - t0, 1), "ended": round(time.time(), 1)}


def game_part(row: dict) -> dict:
    """What of ``row`` the game alone decides (compare two runs of a tournament by it)."""
    return {k: row.get(k) for k in GAME_FIELDS}
