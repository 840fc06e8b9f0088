"""What a node can reach while it runs: :class:`RunContext`.

The context holds the robot backend, the clock (never ``time.time()``), the
task parameters, a logger, the tree's blackboard and ``services``: an open
mapping for shared things such as the world map, a perception pipeline or
the navigation stack.  The agent fills ``services``; a plug-in can also
register a factory with :func:`register_service` so that a service is made
on first use (``ctx.service("nav")``) when nobody provided one, which is how
``rll-bt tree run`` gets the skills' services without the agent.
"""
from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from ..clock import Clock, WallClock
from .blackboard import Blackboard
from .errors import TreeRuntimeError

_SERVICE_FACTORIES: dict[str, Callable[[RunContext], Any]] = {}


def register_service(name: str, factory: Callable[[RunContext], Any], *, replace: bool = False) -> None:
    """Make ``ctx.service(name)`` build the service with ``factory(ctx)`` on
    first use, when the context was not given one."""
    if name in _SERVICE_FACTORIES and not replace and _SERVICE_FACTORIES[name] is not factory:
        raise ValueError(f"a service factory named {name!r} is already registered")
    _SERVICE_FACTORIES[name] = factory


def service_factories() -> dict[str, Callable]:
    return dict(_SERVICE_FACTORIES)


@dataclass
class RunContext:
    """Everything a node needs besides its ports.

    - ``backend``: the robot (:class:`rll_bt.backend.Backend`) or None
    - ``clock``: time for waits and timeouts (seconds)
    - ``task``: the task parameters, read-only (``$task.NAME`` in YAML)
    - ``logger``: where nodes log
    - ``services``: named shared objects (world map, perception, ...)
    - ``blackboard``: the tree's blackboard (set by the loader)
    """
    backend: Any = None
    clock: Clock = field(default_factory=WallClock)
    task: Mapping[str, Any] = field(default_factory=dict)
    logger: logging.Logger = field(default_factory=lambda: logging.getLogger("rll_bt.tree"))
    services: dict[str, Any] = field(default_factory=dict)
    blackboard: Blackboard = field(default_factory=Blackboard)

    def __post_init__(self) -> None:
        self.task = MappingProxyType(dict(self.task))

    def service(self, name: str) -> Any:
        """The service ``name``, made by its registered factory if needed."""
        try:
            return self.services[name]
        except KeyError:
            pass
        factory = _SERVICE_FACTORIES.get(name)
        if factory is None:
            known = ", ".join(sorted(set(self.services) | set(_SERVICE_FACTORIES))) or "none"
            raise TreeRuntimeError(f"no service named {name!r} in the run context (available: {known})")
        svc = self.services[name] = factory(self)
        return svc

    def has_service(self, name: str) -> bool:
        return name in self.services or name in _SERVICE_FACTORIES

    def with_task(self, task: Mapping[str, Any]) -> RunContext:
        """A copy of this context for a new task (fresh blackboard)."""
        return RunContext(self.backend, self.clock, task, self.logger, self.services, Blackboard())
