"""The command lines and configurations of a ``--processes`` game's children.

- :func:`teamserver_config`: what ``python -m games.child`` reads to run a
  team server process (its message log is added per start);
- :func:`agent_command`: the ``rll-bt agent`` command line of one robot.
"""
from __future__ import annotations

import sys
from pathlib import Path

from rll_bt.comm import Layout

from .options import GameOptions
from .teams import Team

__all__ = ["CLI_MAIN", "agent_command", "teamserver_config"]

CLI_MAIN = "import sys; from rll_bt.cli import main; sys.exit(main())"
CHANNELS = ("public", "cyan", "magenta")


class ChildExited(RuntimeError):
    """A process of the game ended on its own (or never came up)."""


def teamserver_config(o: GameOptions, t: Team, name: str, *, folder: Path, refbox_host: str, layout: Layout,
                      listen: int, truth: dict, legacy: bool) -> dict:
    """Team ``t``'s server process ``name`` (its files in ``folder``), the agents'
    port ``listen``, the refbox's UDP ``layout``; ``truth``: the stations' zones
    (for the oracle strategy); ``legacy``: a game of one team (names as before two)."""
    robot = {ch: [layout.robot(ch).send, layout.robot(ch).recv] for ch in CHANNELS}
    return {"profile": o.profile, "team": t.name, "key": t.key, "refbox_host": refbox_host,
            "ports": robot, "listen": listen, "state": str(folder / f"{name}.sqlite"), "strategy": t.strategy,
            "seed": o.seed, "baseline": t.baseline, "map_period": o.map_period,
            "snapshot": str(folder / f"{name}.json"), "teamserver": t.teamserver,
            "oracle": truth if t.strategy == "oracle" else None,
            "extra": t.spec.server_settings if t.spec is not None else {},
            "log_channel": "teamserver" if legacy else name, "robot_prefix": "" if legacy else f"{t.prefix}-"}


def agent_command(o: GameOptions, t: Team, n: int, *, backend: list[str], teamserver_port: int, refbox_host: str,
                  layout: Layout, pose=None, first_start: bool, legacy: bool, extra: list[str]) -> list[str]:
    """Robot ``n`` of team ``t`` as an ``rll-bt agent`` process: ``backend`` its
    backend arguments, ``pose`` its start pose (None: it localises globally),
    ``extra`` further arguments (faults, recording)."""
    pub, chan = layout.robot("public"), layout.robot(t.color.lower())
    start = [f"--start-pose={pose.x},{pose.y},{pose.theta}"] if pose is not None else []
    peer = [] if legacy else ["--name", f"{t.prefix}-R{n}"]
    return [sys.executable, "-c", CLI_MAIN, "agent", "--robot", str(n), "--team", t.name,
            "--key", t.key, "--profile", o.profile, *backend, *peer,
            "--teamserver", f"127.0.0.1:{teamserver_port}", "--refbox-host", refbox_host, "--layout", "sim",
            "--public-recv", str(pub.recv), "--public-send", str(pub.send),
            "--team-recv", str(chan.recv), "--team-send", str(chan.send), *start, "--hz", str(o.hz),
            "--localisation", o.localisation, "-q", *extra] + (["--first-start"] if first_start else [])
