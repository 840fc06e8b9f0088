"""The simulated refbox's package shape: one module per rule set and per station type,
no import circles inside the package (no module over 500 lines is checked for every package
by tests/rll_bt/kernel/test_import_direction.py)."""
from __future__ import annotations

import ast
from pathlib import Path

from tests.support import REPO

PKG = REPO / "backends" / "sim" / "refbox"
NAME = "backends.sim.refbox"


def _module_name(path: Path) -> str:
    rel = path.relative_to(PKG).with_suffix("")
    parts = [p for p in rel.parts if p != "__init__"]
    return ".".join([NAME, *parts])


def _imports(path: Path) -> set[str]:
    """Modules of the package ``path`` imports (relative or absolute), at module level or
    inside a function (a deferred import is still a circle)."""
    me = _module_name(path)
    package = me if path.name == "__init__.py" else me.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            names = [mod] + [f"{mod}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        out |= {n for n in names if n.startswith(NAME)}
    return out


def _graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in PKG.rglob("*.py")}
    return {m: {i for i in _imports(p) if i in files and i != m} for m, p in files.items()}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            # a package importing its own submodules is how a package is assembled
            if m == n.rsplit(".", 1)[0]:
                continue
            if state.get(n) == 1:
                return stack[stack.index(n):] + [n]
            if n not in state:
                found = visit(n)
                if found:
                    return found
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def test_the_refbox_package_has_no_import_circle():
    assert _cycle(_graph()) is None, " -> ".join(_cycle(_graph()))


def test_the_circle_check_finds_one():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]


def test_one_module_per_rule_set_and_per_station_type():
    assert {p.stem for p in (PKG / "rulesets").glob("*.py")} == {"__init__", "rcll2016",
                                                                  "rcll2025"}
    assert {p.stem for p in (PKG / "stations").glob("*.py")} == {
        "__init__", "base", "lights", "bs", "rs", "cs", "ds", "ss"}
