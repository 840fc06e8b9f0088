"""The task kinds whose trees the agent runs, and what it reads back from them.

The tasks themselves arrive as the league's AgentTask (+ rll-bt's
TaskDetail) and are read by :mod:`rll_bt.agenttask`; a kind is the name of
its tree (``trees/<kind>.yaml``).
"""
from __future__ import annotations

from ..agenttask import KINDS

#: kinds that run a tree
TREE_KINDS = KINDS
#: what the agent reads from a task tree that succeeded: kind -> {output name: type}; the
#: tree declares these under ``outputs:`` (explore_zone: the stations seen, for ZoneExplored)
TREE_OUTPUTS: dict[str, dict[str, str]] = {"explore_zone": {"found": "list"}}


def output_problems(kind: str, spec) -> list[str]:
    """What the tree ``spec`` of ``kind`` lacks of the outputs the agent reads."""
    out = []
    for name, tname in TREE_OUTPUTS.get(kind, {}).items():
        decl = spec.outputs.get(name)
        if decl is None:
            out.append(f"{kind}.yaml declares no output {name!r} ({tname}), which the agent reads")
        elif decl.ptype.name != tname:
            out.append(f"{kind}.yaml declares output {name!r} as {decl.ptype.name}; the agent reads a {tname}")
    return out
