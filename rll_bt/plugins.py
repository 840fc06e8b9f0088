"""Entry-point discovery for the plug-in groups.

``rll_bt`` never imports ``skills``, ``backends`` or ``teamserver`` by name;
it finds what they provide through these groups:

- ``rll_bt.backends``: name -> a :class:`rll_bt.backend.Backend` subclass or factory
- ``rll_bt.nodes``: name -> a module (or callable) registering tree node types
- ``rll_bt.commands``: name -> a ``register(cli)`` function adding CLI commands
- ``rll_bt.simulators``: name -> a factory of a simulated game (world, refbox, robots) for ``rll-bt sim``
- ``rll_bt.teamservers``: name -> a factory of an in-process team server for ``rll-bt sim``

A plug-in publishes the values its options take (exploration strategies,
localisation presets, perception modes) on its entry point's object
(:func:`offers`); the command line and the games read them with
:func:`choices` instead of keeping copies of the lists.
"""
from __future__ import annotations

import logging
from collections.abc import Sequence
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


# -- option choices the plug-ins publish -------------------------------------------------------
def offers(**choices):
    """Decorate an entry point's object with the option choices it publishes::

        @offers(strategy=("algorithm1", "random"))
        def open_teamserver(**options): ...

    Each keyword is an option name, its value the allowed values (in order,
    the preferred first).  Read back with :func:`choices`.  (A module used
    as an entry point publishes a ``choices`` dict of its own.)"""
    def mark(obj):
        published = dict(getattr(obj, "choices", None) or {})
        published.update({k: tuple(v) for k, v in choices.items()})
        obj.choices = published
        return obj
    return mark


def choices(group: str, option: str, name: str | None = None) -> tuple[str, ...]:
    """The values of ``option`` that the entry points of ``group`` publish
    (only entry point ``name`` when given), in the order they give them,
    each once.  Empty when none publishes it."""
    objs = {name: load(group, name)} if name is not None else load_all(group)
    out: dict[str, None] = {}
    for _n, obj in sorted(objs.items()):
        for value in (getattr(obj, "choices", None) or {}).get(option, ()):
            out[value] = None
    return tuple(out)


class Choices(Sequence):
    """:func:`choices` loaded on first use, for ``argparse``'s ``choices=``:
    building the command line then imports no plug-in; checking a value
    given, ``--help`` and an error message do.  Give the argument a
    ``metavar`` (argparse lists the choices in the usage otherwise, which
    loads them) and ``%(choices)s`` in its help."""

    def __init__(self, group: str, option: str, name: str | None = None):
        self.group, self.option, self.name = group, option, name
        self._values: tuple[str, ...] | None = None

    @property
    def values(self) -> tuple[str, ...]:
        if self._values is None:
            self._values = choices(self.group, self.option, self.name)
        return self._values

    def __getitem__(self, i):
        return self.values[i]

    def __len__(self) -> int:
        return len(self.values)

    def __contains__(self, value) -> bool:
        return value in self.values

    def __repr__(self) -> str:
        return f"Choices({self.group!r}, {self.option!r}: {', '.join(self.values)})"
