"""The team server's shape (docs/architecture.md), enforced on the source tree:

- sub-packages import one way: knowledge <- links, planning <- production
  <- dispatch <- exploration <- the server and its entry points (cli, game,
  status) at the top; no import circle between modules;
- no mixins: every class has at most one base class, and none is named
  ``*Mixin``.

(No module over 500 lines is checked for every package by
tests/rll_bt/kernel/test_import_direction.py.)
"""
import ast
from pathlib import Path

from tests.support import REPO

ROOT = REPO / "teamserver"
#: sub-package -> the sub-packages it may import
ALLOWED = {
    "knowledge": set(),
    "links": {"knowledge"},
    "planning": {"knowledge"},
    "production": {"knowledge", "planning"},
    "dispatch": {"knowledge", "links", "planning", "production"},
    "exploration": {"knowledge", "links", "dispatch"},
}
TOP = {"server", "cli", "game", "status"}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """Team-server modules (or packages) ``path`` imports, absolute or relative,
    also inside functions."""
    name = module_name(path)
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            target = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                full = f"{target}.{alias.name}"
                out.add(full if (REPO / full.replace(".", "/")).with_suffix(".py").exists()
                        or (REPO / full.replace(".", "/")).is_dir() else target)
        elif isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names}
    return {m for m in out if m.split(".")[0] == "teamserver"}


def sources() -> list[Path]:
    return sorted(ROOT.rglob("*.py"))


def sub_package(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_sub_packages_import_one_way():
    bad = []
    for path in sources():
        src = sub_package(module_name(path))
        for target in imports(path):
            dst = sub_package(target)
            if src in TOP or dst is None or dst == src:
                continue
            if dst in TOP or dst not in ALLOWED.get(src, set()):
                bad.append(f"{path.relative_to(REPO)} imports {target}")
    assert bad == []
    names = {p.name for p in ROOT.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert names == set(ALLOWED)
    assert {p.stem for p in ROOT.glob("*.py")} == TOP | {"__init__"}


def test_no_import_circle():
    graph = {module_name(p): {t for t in imports(p) if t != module_name(p)} for p in sources()}
    done: set[str] = set()

    def visit(m: str, path: tuple[str, ...]) -> None:
        assert m not in path, " -> ".join(path + (m,))
        if m in done:
            return
        for t in sorted(graph.get(m, ())):
            if not m.startswith(t + "."):         # a module importing its own package
                visit(t, path + (m,))
        done.add(m)

    for m in sorted(graph):
        visit(m, ())


def test_no_mixins():
    for path in sources():
        text = path.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                assert not node.name.endswith("Mixin"), f"{path}: {node.name}"
                assert len(node.bases) <= 1, f"{path}: {node.name} has {len(node.bases)} bases"
