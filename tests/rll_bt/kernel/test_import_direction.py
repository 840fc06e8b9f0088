"""DESIGN.md's import direction, enforced on the source tree.

- rll_bt never imports skills, backends, teamserver or games (it uses entry points);
- skills never imports a concrete backend (only rll_bt.backend);
- backends never imports skills or teamserver;
- games (the application) finds every plug-in through entry points, and no
  plug-in imports the application.
"""
import ast
from pathlib import Path

import pytest

from tests.support import REPO

ROOT = REPO

FORBIDDEN = {
    "rll_bt": {"skills", "backends", "teamserver", "games"},
    "skills": {"backends", "games"},
    "backends": {"skills", "teamserver", "games"},
    "teamserver": {"games"},
    "games": {"skills", "backends", "teamserver"},
}


def imported_roots(path: Path):
    """(line, top-level package) of every absolute import in a file, also
    those inside functions and importlib.import_module("...") literals."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module.split(".")[0]
        elif (isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None))
              in ("import_module", "__import__") and node.args
              and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)):
            yield node.lineno, node.args[0].value.split(".")[0]


def violations(package: str):
    bad = []
    for path in sorted((ROOT / package).rglob("*.py")):
        for line, root in imported_roots(path):
            if root in FORBIDDEN[package]:
                bad.append(f"{path.relative_to(ROOT)}:{line}: imports {root}")
    return bad


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_import_direction(package):
    assert (ROOT / package).is_dir()
    assert violations(package) == []


def test_checker_catches_a_violation(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def f():\n    import backends.sim\n    from teamserver import x\n"
                 "import importlib\nimportlib.import_module('skills.nav')\n")
    assert [r for _, r in imported_roots(f)] == ["importlib", "backends", "teamserver", "skills"]
