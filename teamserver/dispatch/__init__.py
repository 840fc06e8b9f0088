"""Dispatch: ready tasks to robots, PrepareMachine at the right moment, task
results, robots and stations that drop out.  :mod:`.dispatcher` wires the
collaborators together; :class:`DispatchConfig` (:mod:`.config`) steers
them.  See ``docs/architecture.md``."""
from .config import DispatchConfig

__all__ = ["DispatchConfig"]
