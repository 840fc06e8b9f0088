"""DESIGN.md's import direction, enforced on the source tree.

Between packages:
- rll_bt never imports skills, backends, teamserver or games (it uses entry points);
- skills never imports a concrete backend (only rll_bt.backend);
- backends never imports skills or teamserver;
- teamserver imports neither skills nor backends;
- games (the application) finds every plug-in through entry points, and no
  plug-in imports the application.

Inside the kernel: its inner layers (comm, msgs, rules, backend, tree, and the
clock, errors, plug-in discovery and contracts they share) import nothing of
the agent runtime, game orchestration or the command line.

Anywhere: no import circles between modules, counting the imports inside
functions too (a deferred import that closes a circle is still a circle); and
no module over 500 lines, in the packages, the tests and the benchmark scripts.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.support import REPO

ROOT = REPO
PACKAGES = ("rll_bt", "skills", "backends", "teamserver", "games", "trees")

FORBIDDEN = {
    "rll_bt": {"skills", "backends", "teamserver", "games"},
    "skills": {"backends", "games"},
    "backends": {"skills", "teamserver", "games"},
    "teamserver": {"skills", "backends", "games"},
    "games": {"skills", "backends", "teamserver"},
}

#: the kernel's inner layers, and what they must not import
INNER = ("rll_bt.comm", "rll_bt.msgs", "rll_bt.rules", "rll_bt.backend", "rll_bt.tree", "rll_bt.clock",
         "rll_bt.errors", "rll_bt.plugins", "rll_bt.contracts")
OUTER = ("rll_bt.agent", "rll_bt.cli", "games")


# -- reading the imports -------------------------------------------------------------------------
def import_nodes(tree: ast.AST):
    """Every import statement (also inside functions), and importlib literals as (line, name)."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif (isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None))
              in ("import_module", "__import__") and node.args
              and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
            yield ast.Import(names=[ast.alias(name=node.args[0].value)], lineno=node.lineno)


def modules(root: Path = ROOT) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package) for every source module."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            is_pkg = parts[-1] == "__init__"
            out[".".join(parts[:-1] if is_pkg else parts)] = (path, is_pkg)
    return out


def imported(name: str, is_pkg: bool, node, known) -> list[str]:
    """The dotted modules ``node`` (in module ``name``) imports: ``from P import X``
    imports module ``P.X`` when there is one, else ``P`` itself."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level:
        base = (name if is_pkg else name.rpartition(".")[0]).split(".")
        base = base[:len(base) - (node.level - 1)]
        mod = ".".join(base + ([node.module] if node.module else []))
    else:
        mod = node.module or ""
    return [f"{mod}.{a.name}" if f"{mod}.{a.name}" in known else mod for a in node.names]


def import_graph(root: Path = ROOT) -> dict[str, dict[str, int]]:
    """module -> {module it imports: line}, among the source modules."""
    known = modules(root)
    graph: dict[str, dict[str, int]] = {}
    for name, (path, is_pkg) in known.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in import_nodes(tree):
            for target in imported(name, is_pkg, node, known):
                if target in known and target != name:
                    graph.setdefault(name, {}).setdefault(target, node.lineno)
    return graph


def circles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0

    def visit(v: str) -> None:
        nonlocal counter
        index[v] = low[v] = counter
        counter += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, {}):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def describe(group: list[str], graph, root: Path = ROOT) -> str:
    """One circle of ``group`` with the file and line of every import on it."""
    known = modules(root)
    members = set(group)
    path, seen = [group[0]], {group[0]}
    while True:                                     # walk inside the group until a module repeats
        nxt = sorted(w for w in graph.get(path[-1], {}) if w in members)
        step = next((w for w in nxt if w == group[0] or w not in seen), nxt[0])
        path.append(step)
        if step in seen:
            break
        seen.add(step)
    path = path[path.index(path[-1]):]
    hops = [f"{known[a][0].relative_to(root)}:{graph[a][b]} ({a} imports {b})" for a, b in zip(path, path[1:])]
    return " -> ".join(path) + "\n    " + "\n    ".join(hops)


# -- the rules -----------------------------------------------------------------------------------
def violations(package: str):
    bad = []
    for path in sorted((ROOT / package).rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in import_nodes(tree):
            if isinstance(node, ast.ImportFrom) and node.level:
                continue
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
            for name in names:
                if name.split(".")[0] in FORBIDDEN[package]:
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno}: imports {name.split('.')[0]}")
    return bad


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_import_direction(package):
    assert (ROOT / package).is_dir()
    assert violations(package) == []


def test_the_kernels_inner_layers_import_no_agent_games_or_cli():
    graph = import_graph()
    bad = [f"{modules()[m][0].relative_to(ROOT)}:{line}: {m} imports {t}"
           for m, targets in graph.items() if m.startswith(INNER)
           for t, line in targets.items() if t.startswith(OUTER)]
    assert bad == []


def test_no_import_circles_anywhere():
    graph = import_graph()
    found = circles(graph)
    assert not found, "import circles:\n" + "\n".join(describe(g, graph) for g in found)


MAX_LINES = 500


def long_modules(root: Path = ROOT, folders=PACKAGES + ("tests", "benchmarks")) -> dict[str, int]:
    """Source files over MAX_LINES lines: relative path -> lines."""
    return {str(p.relative_to(root)): n for folder in folders for p in sorted((root / folder).rglob("*.py"))
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}


def test_no_module_over_500_lines_anywhere():
    assert long_modules() == {}


# -- the checker itself --------------------------------------------------------------------------
def test_long_modules_counts_lines(tmp_path):
    (tmp_path / "pkg" / "sub").mkdir(parents=True)
    (tmp_path / "pkg" / "ok.py").write_text("x = 1\n" * MAX_LINES)
    (tmp_path / "pkg" / "sub" / "big.py").write_text("x = 1\n" * (MAX_LINES + 1))
    assert long_modules(tmp_path, ("pkg",)) == {str(Path("pkg/sub/big.py")): MAX_LINES + 1}


def test_checker_reads_every_kind_of_import(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def f():\n    import backends.sim\n    from teamserver import x\n"
                 "import importlib\nimportlib.import_module('skills.nav')\n")
    roots = []
    for node in import_nodes(ast.parse(f.read_text())):
        roots += [a.name.split(".")[0] for a in node.names] if isinstance(node, ast.Import) else [node.module]
    assert sorted(roots) == ["backends", "importlib", "skills", "teamserver"]


def test_checker_finds_circles_through_deferred_and_package_imports(tmp_path):
    pkg = tmp_path / "games"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .a import A\n")
    (pkg / "a.py").write_text("from .sub import helper\nA = 1\n")
    (pkg / "sub" / "__init__.py").write_text("def helper():\n    from .. import A   # deferred\n    return A\n")
    (pkg / "b.py").write_text("from . import a\n")
    for other in PACKAGES:
        (tmp_path / other).mkdir(exist_ok=True)
    graph = import_graph(tmp_path)
    assert graph["games.b"] == {"games.a": 1}
    assert circles(graph) == [["games", "games.a", "games.sub"]]
    text = describe(["games", "games.a", "games.sub"], graph, tmp_path)
    assert text.startswith("games -> games.a -> games.sub -> games")
    assert "games/sub/__init__.py:2 (games.sub imports games)" in text
