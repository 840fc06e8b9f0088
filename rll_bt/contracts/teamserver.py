"""The team-server contract: what a game needs of an in-process team server.

Entry point group ``rll_bt.teamservers``: name -> a factory called as
``factory(profile=..., team_name=..., key=..., clock=..., refbox_public=...,
refbox_team=..., agents=..., state=..., strategy=..., seed=..., oracle=...,
options=...)`` where ``refbox_public`` is a zero-argument factory of the
refbox's public channel, ``refbox_team`` is ``color -> Transport`` (the
team channel once the colour is known) and ``agents`` a zero-argument
factory of the stream server the agents connect to (each called again on a
restart).  The factory publishes the exploration strategies it plays as
``choices["strategy"]`` (:func:`rll_bt.plugins.offers`), the names of the
settings :attr:`TeamServerOptions.extra` may give as ``choices["setting"]``,
and may carry ``factory.check(options)``, raising ``ValueError`` for options
it would refuse (:func:`check_teamserver`), so a tournament of many games
finds a bad setting before its first game.
"""
from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass, field

TEAMSERVERS = "rll_bt.teamservers"


class TeamServerHandle(abc.ABC):
    """An in-process team server (see the module doc)."""

    @abc.abstractmethod
    def tick(self) -> None:
        """One step: read both links, decide, send.  Never blocks."""

    @abc.abstractmethod
    def restart(self) -> None:
        """Kill the server without a goodbye and start a new one on the same
        state database and a fresh agent listener."""

    @abc.abstractmethod
    def snapshot(self) -> dict:
        """Plain-data view for reports: ``robots`` {number: {"task": kind or
        None, "task_id", "status"}}, ``tasks`` [{"id", "kind", "state",
        "robot", "machine", "assigned_at", "finished_at"}], ``known``
        {machine: {property: value}} of the report's properties (zone and
        light in 2016, zone and orientation from 2017) the server is sure of
        (its own reporting confidence), lights as sorted colour tuples, ``stations`` {machine: state as the
        server last heard it} and ``delivered`` (products delivered)."""

    def close(self) -> None:
        pass


@dataclass
class TeamServerOptions:
    """Tuning passed to a team-server factory: ``baseline`` selects the greedy
    one-order-at-a-time production instead of the HTN planner;
    ``map_period`` how often (s) a changed machine map goes to the robots."""

    baseline: bool = False
    map_period: float = 5.0
    extra: dict = field(default_factory=dict)


TeamServerFactory = Callable[..., TeamServerHandle]


def load_teamserver(name: str) -> TeamServerFactory:
    """The ``rll_bt.teamservers`` entry point ``name``; KeyError names the installed ones."""
    from .. import plugins
    return plugins.load(TEAMSERVERS, name)


def check_teamserver(name: str, options: TeamServerOptions) -> None:
    """``ValueError`` when team server ``name`` would refuse ``options`` (its
    factory's ``check``, when it has one); KeyError names the installed ones."""
    check = getattr(load_teamserver(name), "check", None)
    if check is not None:
        check(options)
