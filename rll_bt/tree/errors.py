"""Errors of the tree engine, each naming ``file:line:column``.

Lines and columns are 1-based, as editors show them.
"""
from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass

from ..errors import UserError


@dataclass(frozen=True)
class Loc:
    """A place in a tree file; ``style`` is the YAML scalar style (``'``,
    ``"``, ``|``, ``>`` or None for plain), used to point inside strings."""
    file: str
    line: int
    col: int
    style: str | None = None

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"

    def shifted(self, offset: int) -> Loc:
        """The place ``offset`` characters into a one-line scalar."""
        quote = 1 if self.style in ("'", '"') else 0
        return Loc(self.file, self.line, self.col + quote + offset, None)


UNKNOWN_LOC = Loc("<python>", 0, 0)


@dataclass(frozen=True)
class Diagnostic:
    """One problem found in a tree file."""
    loc: Loc
    message: str
    hint: str = ""

    def __str__(self) -> str:
        text = f"{self.loc}: {self.message}"
        if self.hint:
            text += f"\n  hint: {self.hint}"
        return text


class TreeLoadError(UserError):
    """A tree (or one of its subtrees) cannot be loaded.  ``diagnostics``
    lists every problem found, in file order."""

    def __init__(self, diagnostics: Iterable[Diagnostic]):
        self.diagnostics = sorted(set(diagnostics), key=lambda d: (d.loc.file, d.loc.line, d.loc.col, d.message))
        first = self.diagnostics[0] if self.diagnostics else Diagnostic(UNKNOWN_LOC, "invalid tree")
        super().__init__(first.message, where=str(first.loc), hint=first.hint or None)

    def __str__(self) -> str:
        return "\n".join(str(d) for d in self.diagnostics)


class TreeRuntimeError(RuntimeError):
    """A node could not run: a missing service, a bad value at tick time."""


def did_you_mean(word: str, choices: Iterable[str], what: str = "") -> str:
    """A hint naming the closest choices, or listing a few of them."""
    choices = sorted(set(choices))
    close = difflib.get_close_matches(word, choices, n=3, cutoff=0.6)
    if close:
        return "did you mean " + " or ".join(f"'{c}'" for c in close) + "?"
    if not choices:
        return f"no {what} are available" if what else ""
    shown = ", ".join(choices[:12]) + (", ..." if len(choices) > 12 else "")
    return f"known {what}: {shown}" if what else f"choose one of: {shown}"
