"""The blackboard of one tree: a dict of absolute keys (``/a/b``).

Each loaded tree owns its blackboard, so several robots' trees in one
process (lockstep simulation) never share keys.  Ticking is single-threaded
by design: a tree is ticked from one thread, and code outside the tree (the
agent) reads and writes the blackboard between ticks from that same thread.

Changes are journalled only while a tick log asks for them.  Replace values
rather than mutating them in place, or the journal cannot see the change.
"""
from __future__ import annotations

from collections.abc import Iterator
from typing import Any

UNSET: Any = type("Unset", (), {"__repr__": lambda self: "UNSET"})()


def normalise_key(key: str, scope: str = "/") -> str:
    """An absolute key: ``key`` if it starts with ``/``, else ``scope + key``."""
    if key.startswith("/"):
        return key
    return scope + key


class Blackboard:
    """Absolute keys to values, with an optional change journal."""
    __slots__ = ("_data", "_journal")

    def __init__(self, initial: dict | None = None):
        self._data: dict[str, Any] = {}
        self._journal: dict[str, Any] | None = None
        for k, v in (initial or {}).items():
            self.set(normalise_key(k), v)

    def get(self, key: str, default: Any = None) -> Any:
        return self._data.get(key, default)

    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __contains__(self, key: str) -> bool:
        return key in self._data

    def set(self, key: str, value: Any) -> None:
        self._data[key] = value
        if self._journal is not None:
            self._journal[key] = value

    __setitem__ = set

    def unset(self, key: str) -> None:
        if self._data.pop(key, UNSET) is not UNSET and self._journal is not None:
            self._journal[key] = UNSET

    def exists(self, key: str) -> bool:
        return key in self._data

    def keys(self, prefix: str = "/") -> list[str]:
        return sorted(k for k in self._data if k.startswith(prefix))

    def items(self, prefix: str = "/") -> Iterator[tuple[str, Any]]:
        for k in self.keys(prefix):
            yield k, self._data[k]

    def snapshot(self) -> dict[str, Any]:
        return dict(self._data)

    def clear(self, prefix: str = "/") -> None:
        for k in self.keys(prefix):
            self.unset(k)

    # -- journal (tick logging) ------------------------------------------------
    def start_journal(self) -> None:
        if self._journal is None:
            self._journal = {}

    def drain_journal(self) -> dict[str, Any]:
        """Changes since the last drain; removed keys map to :data:`UNSET`."""
        j = self._journal or {}
        if self._journal is not None:
            self._journal = {}
        return j

    def stop_journal(self) -> None:
        self._journal = None

    def __repr__(self) -> str:
        return f"Blackboard({self._data!r})"


# -- the error a failed tree reports --------------------------------------------
#: absolute keys where ``fail_with_error`` and ``recovery`` leave the reason a
#: tree failed; the agent reads them (``LoadedTree.error()``) and reports them
ERROR_CODE_KEY = "/error/code"
ERROR_MESSAGE_KEY = "/error/message"
ERROR_NODE_KEY = "/error/node"


def write_error(bb: Blackboard, code: str, message: str = "", node: str = "") -> None:
    bb.set(ERROR_CODE_KEY, code)
    bb.set(ERROR_MESSAGE_KEY, message)
    bb.set(ERROR_NODE_KEY, node)


def clear_error(bb: Blackboard) -> None:
    for k in (ERROR_CODE_KEY, ERROR_MESSAGE_KEY, ERROR_NODE_KEY):
        bb.unset(k)
