"""JSON-lines tick log: record every tick of a tree, and read it back.

The first line describes the tree::

    {"kind": "tree", "version": 1, "name": ..., "file": ..., "t": 0.0,
     "nodes": [{"id": 0, "parent": null, "depth": 0, "name": ..., "type": ..., "loc": "f.yaml:9:3"}, ...],
     "blackboard": {"/count": 0}}

then one line per tick::

    {"kind": "tick", "tick": 1, "t": 0.1, "status": "RUNNING",
     "visited": [[3, "SUCCESS"], [4, "RUNNING"], [0, "RUNNING"]],
     "halted": [7], "bb": {"/done": true}, "unset": ["/error/code"]}

``visited`` lists the nodes ticked, in the order they finished their tick;
``halted`` the nodes that were running and were stopped without being
ticked; ``bb`` the blackboard keys written during the tick (values made
JSON-safe) and ``unset`` those removed.  :func:`read_log` and
:func:`replay` read it back; ``rll-bt tree replay`` prints it.
"""
from __future__ import annotations

import dataclasses
import enum
import json
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from py_trees.common import Status

from .blackboard import UNSET

_SHORT = {"SUCCESS": "S", "FAILURE": "F", "RUNNING": "R", "INVALID": "-"}


def jsonable(value: Any, depth: int = 0) -> Any:
    """A JSON-safe rendering of a blackboard value."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if value == value and abs(value) != float("inf") else str(value)
    if depth > 6:
        return repr(value)
    if isinstance(value, enum.Enum):
        return value.name
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name), depth + 1) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): jsonable(v, depth + 1) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [jsonable(v, depth + 1) for v in value]
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        try:
            return jsonable(tolist(), depth + 1)
        except Exception:
            pass
    text = repr(value)
    return text if len(text) <= 200 else text[:197] + "..."


class TickLogger:
    """Writes a tree's ticks to ``out`` (a path or a text stream) as JSON lines.

    Attach with ``TickLogger(tree, "ticks.jsonl")``; call :meth:`close` at the end."""

    def __init__(self, tree, out: str | Path | IO[str]):
        self.tree = tree
        self._own = not hasattr(out, "write")
        self.stream: IO[str] = open(out, "w", encoding="utf-8") if self._own else out  # noqa: SIM115
        self._ids = {id(info.behaviour): info.id for info in tree.nodes}
        self._prev = [info.behaviour.status for info in tree.nodes]
        bb = tree.blackboard
        self._write({"kind": "tree", "version": 1, "name": tree.name,
                     "file": tree.spec.file if tree.spec else None, "t": tree.ctx.clock.now(),
                     "nodes": [{"id": i.id, "parent": i.parent, "depth": i.depth, "name": i.behaviour.name,
                                "type": i.spec.type if i.spec else type(i.behaviour).__name__,
                                "loc": str(i.spec.loc) if i.spec else ""} for i in tree.nodes],
                     "blackboard": {k: jsonable(v) for k, v in bb.items()}})
        bb.drain_journal()
        bb.start_journal()
        tree.add_observer(self._on_tick)

    def _write(self, record: dict) -> None:
        self.stream.write(json.dumps(record, separators=(",", ":")) + "\n")

    def _on_tick(self, tree, visited: list) -> None:
        ids = self._ids
        seen = set()
        vis = []
        for b in visited:
            i = ids.get(id(b))
            if i is not None:
                vis.append([i, b.status.name])
                seen.add(i)
        halted = []
        for info in tree.nodes:
            st = info.behaviour.status
            if info.id not in seen and self._prev[info.id] is Status.RUNNING and st is not Status.RUNNING:
                halted.append(info.id)
            self._prev[info.id] = st
        changes = tree.blackboard.drain_journal()
        rec = {"kind": "tick", "tick": tree.count, "t": tree.ctx.clock.now(), "status": tree.root.status.name,
               "visited": vis}
        if halted:
            rec["halted"] = halted
        bb = {k: jsonable(v) for k, v in changes.items() if v is not UNSET}
        if bb:
            rec["bb"] = bb
        unset = [k for k, v in changes.items() if v is UNSET]
        if unset:
            rec["unset"] = unset
        self._write(rec)

    def close(self) -> None:
        try:
            self.tree.remove_observer(self._on_tick)
        except ValueError:
            pass
        self.tree.blackboard.stop_journal()
        if self._own:
            self.stream.close()
        else:
            self.stream.flush()


def read_log(path: str | Path) -> tuple[dict, list[dict]]:
    """The header and the tick records of a tick log (ValueError if malformed)."""
    header, ticks = None, []
    with open(path, encoding="utf-8") as fh:
        for n, line in enumerate(fh, 1):
            line = line.strip()
            if not line:
                continue
            try:
                rec = json.loads(line)
            except json.JSONDecodeError as exc:
                raise ValueError(f"{path}:{n}: not JSON ({exc.msg})") from None
            if not isinstance(rec, dict):
                raise ValueError(f"{path}:{n}: expected a JSON object")
            if rec.get("kind") == "tree":
                header = rec
            elif rec.get("kind") == "tick":
                ticks.append(rec)
    if header is None:
        raise ValueError(f"{path}: no tree header line; is this a tick log?")
    return header, ticks


def replay(header: dict, ticks: list[dict]) -> Iterator[tuple[dict, dict[str, Any], dict[int, str]]]:
    """Yield (tick record, blackboard after it, status of every node after it)."""
    bb = dict(header.get("blackboard") or {})
    status = {n["id"]: "INVALID" for n in header["nodes"]}
    for rec in ticks:
        bb.update(rec.get("bb") or {})
        for k in rec.get("unset") or ():
            bb.pop(k, None)
        for i, st in rec.get("visited") or ():
            status[i] = st
        for i in rec.get("halted") or ():
            status[i] = "INVALID"
        yield rec, dict(bb), dict(status)


def format_log(header: dict, ticks: list[dict], first: int = 1, last: int | None = None,
               show_tree: bool = False) -> Iterator[str]:
    """Human-readable lines for ticks ``first``..``last``: each tick's
    visited nodes (indented as in the tree), halted nodes and blackboard
    changes; with ``show_tree`` the full tree state and blackboard after the
    last tick shown."""
    nodes = {n["id"]: n for n in header["nodes"]}
    yield f"tree {header.get('name')} ({header.get('file')}), {len(nodes)} nodes, {len(ticks)} ticks"
    final = None
    for rec, bb, status in replay(header, ticks):
        n = rec["tick"]
        if n < first or (last is not None and n > last):
            continue
        final = (rec, bb, status)
        yield f"tick {n}  t={rec['t']:.3f}  {rec['status']}"
        for i, st in sorted(rec.get("visited") or (), key=lambda p: p[0]):
            node = nodes.get(i, {"depth": 0, "name": "?", "type": "?"})
            yield f"  {'  ' * node['depth']}{_SHORT.get(st, st)} {node['type']} {node['name']!r}"
        for i in rec.get("halted") or ():
            node = nodes.get(i, {"name": "?", "type": "?"})
            yield f"  halted: {node['type']} {node['name']!r}"
        for k, v in (rec.get("bb") or {}).items():
            yield f"  bb {k} = {json.dumps(v)}"
        for k in rec.get("unset") or ():
            yield f"  bb {k} removed"
    if show_tree and final is not None:
        rec, bb, status = final
        yield f"state after tick {rec['tick']}:"
        for i, node in sorted(nodes.items()):
            yield f"  {'  ' * node['depth']}{_SHORT.get(status[i], status[i])} {node['type']} {node['name']!r}" \
                  f"  {node.get('loc', '')}"
        yield "blackboard:"
        for k in sorted(bb):
            yield f"  {k} = {json.dumps(bb[k])}"
