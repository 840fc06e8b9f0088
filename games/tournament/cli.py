"""``rll-bt tournament CONFIG... --seeds N``: a round robin of team configurations.

    rll-bt tournament htn baseline --seeds 20 --out tour/          # 40 games, 2 at a time
    rll-bt tournament htn baseline htn:strategy=nearest --seeds 5 --jobs 1
    rll-bt tournament htn baseline --seeds 20 --executor dask --address 10.0.0.5:8786

Every pair of configurations plays every seed in both colours (lockstep
games, deterministic for their seed).  Results go to ``OUT/tournament.sqlite``
as each game ends: run the same command again after a kill or Ctrl-C and it
plays only the games still missing.  Prints the table (wins, losses, draws,
points for and against, best game) and one line per game; writes
``games.csv``, ``table.txt`` and ``scores.png`` to OUT.

Exit codes: 0 every game played, 1 a game failed (its row says why; run
again to retry it), 2 bad arguments or a store of other settings,
3 the executor cannot run here (no Dask, no scheduler at --address),
130 interrupted (the games finished so far are kept).
"""
from __future__ import annotations

import sys
from pathlib import Path

from rll_bt.cli.argtypes import count as _count
from rll_bt.cli.argtypes import seconds as _seconds
from rll_bt.errors import Unavailable, UserError


def register(cli) -> None:
    from rll_bt import rules

    from .executors import EXECUTORS
    p = cli.command("tournament", "a round robin of team configurations over many seeded games")
    p.description = " ".join(__doc__.split("\n\n")[2].split())
    p.epilog = ("exit codes: 0 every game played, 1 a game failed, 2 bad arguments, 3 executor unreachable, "
                "130 interrupted (finished games are kept)")
    p.add_argument("configs", nargs="+", metavar="CONFIG",
                   help="team configurations (as rll-bt sim --cyan: htn, baseline, htn:strategy=nearest, ...)")
    p.add_argument("--seeds", type=_count, default=10, metavar="N", help="seeds per pair and colour (default 10)")
    p.add_argument("--first-seed", type=int, default=1, metavar="S", help="the first seed (default 1)")
    p.add_argument("--out", type=Path, default=Path("tournament"), metavar="DIR",
                   help="the store and the outputs (default ./tournament); the same DIR resumes")
    g = p.add_argument_group("games")
    g.add_argument("--profile", default=rules.DEFAULT, choices=rules.PROFILES,
                   help="rules profile (default %(default)s)")
    g.add_argument("--robots", type=int, default=3, choices=(1, 2, 3),
                   help="robots per team unless a CONFIG says robots=N (default 3)")
    g.add_argument("--strategy", default="algorithm1", metavar="NAME",
                   help="exploration strategy unless a CONFIG says strategy=... (default algorithm1)")
    g.add_argument("--setup", type=_seconds, default=10.0, metavar="S", help="SETUP length (default 10)")
    g.add_argument("--exploration", type=_seconds, metavar="S", help="exploration length (default: the rules')")
    g.add_argument("--production", type=_seconds, metavar="S", help="PRODUCTION length (default: the rules')")
    g.add_argument("--overtime", type=_seconds, metavar="S",
                   help="what a tie adds to PRODUCTION (default: the rules' 300 s; 0: a tie ends the game)")
    g = p.add_argument_group("running")
    g.add_argument("--executor", default="local", choices=EXECUTORS,
                   help="local: a process pool here (default); dask: a Dask distributed cluster "
                        "(the tournament extra; see docs/tournaments.md)")
    g.add_argument("--address", metavar="HOST:PORT",
                   help="the Dask scheduler (default with --executor dask: a local cluster of --jobs workers)")
    g.add_argument("--jobs", type=_count, default=2, metavar="N",
                   help="games at a time on this machine (default 2; with --address the cluster's workers decide)")
    g.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..options import GameOptions
    from . import run_tournament
    from .executors import ExecutorUnavailable
    from .schedule import normalise, round_robin, settings
    from .store import StoreError
    if args.address and args.executor == "local":
        raise UserError("--address names a Dask scheduler: give --executor dask", where="--address")
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    game = {"profile": args.profile, "robots": args.robots, "strategy": args.strategy, "setup": args.setup,
            "exploration": args.exploration, "production": args.production, "overtime": args.overtime}
    try:
        configs = normalise(args.configs)
        for m in round_robin(configs, seeds[:1], settings(**game)):       # a bad CONFIG before any game
            from .play import options_for
            options_for(m)
        GameOptions(seed=seeds[0])
    except ValueError as exc:
        raise UserError(str(exc)) from None
    try:
        out = run_tournament(configs, seeds, args.out, executor=args.executor, jobs=args.jobs,
                             address=args.address, progress=not args.quiet, **game)
    except StoreError as exc:
        raise UserError(str(exc), where=f"--out {args.out}") from None
    except ExecutorUnavailable as exc:
        raise Unavailable(str(exc), where=f"--executor {args.executor}") from None
    print(out["table"])
    print()
    print(out["games"])
    print(f"\nwrote {', '.join(out['files'])} to {args.out}", file=sys.stderr)
    return 1 if out["failed"] else 0
