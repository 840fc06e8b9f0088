"""Many lockstep games in worker processes, for the benchmarks.

    rows = run_batch([GameOptions(seed=s) for s in range(1, 31)], jobs=2)

Each game runs in a fresh process of a ``spawn`` pool (one PyBullet world
at a time per worker) and returns its report summary (:mod:`.report`) plus
``wall_time``; a game that raises returns ``{"error": ...}`` instead, so one
bad seed does not lose a long run.  ``stop="explored"`` ends a game as soon
as every exploration point is scored, i.e. every own station is reported
right (the exploration benchmark's measure).  ``done(i, row)`` is called
in the parent as results arrive (progress).
"""
from __future__ import annotations

import multiprocessing as mp
import statistics
import traceback
from collections.abc import Callable, Iterable

from .options import GameOptions, max_exploration_points
from .report import exploration_points


def explored(game) -> bool:
    """Every exploration point scored: every own station reported right."""
    return exploration_points(game.refbox.awards(), "CYAN") >= max_exploration_points(game.options.rules)


STOPS: dict[str, Callable | None] = {"explored": explored, None: None}


def play_one(args: tuple[GameOptions, str | None]) -> dict:
    options, stop = args
    from rll_bt.clock import WallClock

    from . import finish
    from .lockstep import LockstepGame
    wall = WallClock()
    t0 = wall.now()
    try:
        with LockstepGame(options) as game:
            result = game.run(stop=STOPS[stop])
            summary = finish(result, options, wall.now() - t0)
        summary.pop("awards", None)
        return summary
    except Exception as exc:
        return {"seed": options.seed, "strategy": options.strategy, "baseline": options.baseline,
                "error": f"{type(exc).__name__}: {exc}", "trace": traceback.format_exc()}


def run_batch(games: Iterable[GameOptions], *, jobs: int = 2, stop: str | None = None,
              done: Callable[[int, dict], None] | None = None) -> list[dict]:
    """Summaries in the order of ``games``."""
    work = [(g, stop) for g in games]
    out: list[dict | None] = [None] * len(work)
    if jobs <= 1:
        for i, item in enumerate(work):
            out[i] = play_one(item)
            if done:
                done(i, out[i])
        return out  # type: ignore[return-value]
    ctx = mp.get_context("spawn")
    with ctx.Pool(jobs, maxtasksperchild=4) as pool:
        for i, row in pool.imap_unordered(_indexed, list(enumerate(work))):
            out[i] = row
            if done:
                done(i, row)
    return out  # type: ignore[return-value]


def _indexed(item):
    i, args = item
    return i, play_one(args)


def median(values) -> float | None:
    vals = [v for v in values if v is not None]
    return statistics.median(vals) if vals else None


def mean(values) -> float | None:
    vals = [v for v in values if v is not None]
    return statistics.fmean(vals) if vals else None


def fmt(value, spec: str = ".1f", none: str = "-") -> str:
    return none if value is None else format(value, spec)
