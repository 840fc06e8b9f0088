"""Entry-point discovery for the plug-in groups.

``rll_bt`` never imports ``skills``, ``backends`` or ``teamserver`` by name;
it finds what they provide through these groups:

- ``rll_bt.backends``: name -> a :class:`rll_bt.backend.Backend` subclass or factory
- ``rll_bt.nodes``: name -> a module (or callable) registering tree node types
- ``rll_bt.commands``: name -> a ``register(cli)`` function adding CLI commands
- ``rll_bt.simulators``: name -> a factory of a simulated game (world, refbox, robots) for ``rll-bt sim``
- ``rll_bt.teamservers``: name -> a factory of an in-process team server for ``rll-bt sim``
"""
from __future__ import annotations

import logging
from functools import cache
from importlib.metadata import EntryPoint, entry_points

log = logging.getLogger(__name__)

GROUPS = ("rll_bt.backends", "rll_bt.nodes", "rll_bt.commands", "rll_bt.simulators",
          "rll_bt.teamservers")


@cache
def discover(group: str) -> dict[str, EntryPoint]:
    """Entry points of ``group`` by name (not yet loaded)."""
    return {ep.name: ep for ep in entry_points(group=group)}


def load(group: str, name: str):
    """Load one entry point; ``KeyError`` names what is available."""
    eps = discover(group)
    if name not in eps:
        known = ", ".join(sorted(eps)) or "none installed"
        raise KeyError(f"no {group} entry point named {name!r} (available: {known})")
    return eps[name].load()


def load_all(group: str) -> dict[str, object]:
    """Load every entry point of ``group``; a broken plug-in is logged, not fatal."""
    out = {}
    for name, ep in discover(group).items():
        try:
            out[name] = ep.load()
        except Exception as exc:  # a third-party plug-in must not take us down
            log.warning("cannot load %s entry point %r (%s): %s", group, name, ep.value, exc)
    return out
