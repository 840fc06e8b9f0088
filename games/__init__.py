"""Whole simulated games: refbox, world, team server and agents together.

    from games import GameOptions, LockstepGame, play
    summary = play(GameOptions(seed=3, out=Path("game")))   # what ``rll-bt sim`` does
    summary["points"]["total"], summary["table"]

    with LockstepGame(GameOptions(seed=3, production=120)) as game:
        game.run_for(200.0)                 # simulated seconds
        game.kill_agent(2); game.run_for(30.0); game.start_agent(2)
        game.restart_teamserver(); game.station_down("C-CS1", 60.0)
        result = game.run()

An application above the kernel (``rll_bt``), registered like any other
through the ``rll_bt.commands`` entry point ``games`` (``rll-bt sim``).  It
never imports a plug-in by name: the simulator (world and simulated
refbox), the team server and the robots' backends are found through their
entry points (groups ``rll_bt.simulators``, ``rll_bt.teamservers``,
``rll_bt.backends``; contracts in :mod:`rll_bt.contracts` and
:mod:`rll_bt.backend`).

- :mod:`.options`: what one game is (:class:`GameOptions`);
- :mod:`.lockstep`: one process on one simulated clock (:class:`LockstepGame`);
- :mod:`.processes`: every part its own process on loopback sockets
  (:class:`~.processes.ProcessGame`; :mod:`.child` runs its team server,
  :mod:`.teamlog` merges what the processes logged);
- :mod:`.external`: the same against a refbox elsewhere, the real one
  (:class:`~.external.ExternalGame`, ``rll-bt sim --refbox external``);
- :mod:`.recorder`, :mod:`.report`, :mod:`.plots`: what a game did, as
  ``report.json``, a table and PNGs (``messages.jsonl`` is
  :mod:`rll_bt.comm.msglog`'s);
- :mod:`.progress`: the progress line; :mod:`.batch`: many games in worker
  processes (the benchmarks); :mod:`.cli`: ``rll-bt sim``;
- :mod:`.teams`: who plays (``--cyan CONFIG --magenta CONFIG``, two teams
  on one field); :mod:`.tournament`: round robins of configurations
  (``rll-bt tournament``) on a local pool or a Dask cluster.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from pathlib import Path

from .lockstep import GameResult, LockstepGame
from .options import GameOptions, max_exploration_points

__all__ = ["GameResult", "LockstepGame", "GameOptions", "max_exploration_points", "play", "finish",
           "sigterm_interrupts"]


def play(options: GameOptions, *, progress: bool = False, clock=None) -> dict:
    """Play one game as ``rll-bt sim`` does; returns the report summary with
    ``table`` (text) and ``files`` (names written to ``options.out``)."""
    from rll_bt.clock import WallClock
    clock = clock or WallClock()
    t0 = clock.now()
    with sigterm_interrupts():
        result = _play(options, bar=_bar(options, progress, clock), clock=clock)
    return finish(result, options, clock.now() - t0)


@contextmanager
def sigterm_interrupts():
    """SIGTERM raises KeyboardInterrupt in the main thread while a game runs, so
    the game's ``close`` stops every process it started (a ``kill PID`` of
    ``rll-bt sim`` or of a benchmark left the team server, agents and devices
    running without a parent) and ``rll-bt sim`` exits 130 as on Ctrl-C."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt
    old = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _bar(options: GameOptions, progress: bool, clock):
    from .progress import ProgressBar
    colors = tuple(options.lineup())
    return (ProgressBar(options.expected_duration(), clock=clock, team=colors if len(colors) > 1 else colors[0])
            if progress else None)


def _play(options: GameOptions, *, bar, clock) -> GameResult:
    if options.refbox == "external":
        from .external import ExternalGame
        game = ExternalGame(options, progress=bar, clock=clock, connect_timeout=options.refbox_timeout)
    elif options.hardware == "emulated":
        from .hardware import HardwareGame
        game = HardwareGame(options, progress=bar, clock=clock)
    elif options.processes:
        from .processes import ProcessGame
        game = ProcessGame(options, progress=bar, clock=clock)
    else:
        # a game watched live (--gui, --live, --view) keeps to real time, or to --speed
        game = LockstepGame(options, progress=bar, pace=clock if options.pace > 0 else None)
        import sys
        if game.watch is not None and game.watch.port is not None:
            print(f"Foxglove live: open connection ws://localhost:{game.watch.port}", file=sys.stderr)
        if game.view is not None:
            print(f"live view: open {game.view.url} in a browser", file=sys.stderr)
    try:
        result = game.run()
        if bar is not None:
            bar.done(result.sim_time, result.status)
    finally:
        game.close()
    return result


def finish(result: GameResult, options: GameOptions, wall_time: float | None = None) -> dict:
    """The summary of a played game; with ``options.out`` also report.json and the PNGs."""
    from . import report
    summary = report.summarise(result, options, wall_time=wall_time)
    files: list[str] = []
    if options.out is not None:
        from .plots import draw_all
        out = Path(options.out)
        report.write_json(summary, out / "report.json")
        files.append("report.json")
        files += [p.name for p in draw_all(options.rules, result, out)]
        if (out / "messages.jsonl").exists():
            files.insert(0, "messages.jsonl")
    summary["table"] = report.table(summary)
    summary["files"] = files
    return summary
