"""A small HTN engine with partially ordered task networks.

A *task* is a tuple ``(name, *args)``.  A *primitive* task is turned into one
plan step by its operator; a *compound* task is decomposed by the first of
its methods that applies.  Methods return a network *spec* built from tasks
and two combinators:

- ``Seq(a, b, c)``: a before b before c (every last step of a precedes every
  first step of b);
- ``Par(a, b)``: no order between a and b (SHOP's ``:unordered``).

so ``Seq(Par(chain, extras), mount)`` says "the chain and the extra bases in
any order or interleaved, then mount".  The result is a DAG of steps.

Search is depth-first with backtracking over methods *and* over sibling
subtasks (a later subtask that cannot be decomposed makes the engine try the
next method of an earlier one), lazily through generators, so the first plan
costs no more than the choices it has to undo.  There is no state copying:
methods read a planning context (what stations exist and work, ring costs,
...) and express choices as alternative methods.  ``max_expansions`` bounds
the search.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any


class Seq(tuple):
    """Ordered subtasks."""

    def __new__(cls, *items):
        return super().__new__(cls, items)


class Par(tuple):
    """Unordered subtasks."""

    def __new__(cls, *items):
        return super().__new__(cls, items)


@dataclass
class Step:
    """One primitive step of a plan: operator name and its fields."""

    op: str
    fields: dict[str, Any]


@dataclass
class Network:
    """Steps and precedence edges ``(before, after)`` by step index."""

    steps: list[Step] = field(default_factory=list)
    edges: set[tuple[int, int]] = field(default_factory=set)
    sources: list[int] = field(default_factory=list)   # steps with nothing before (locally)
    sinks: list[int] = field(default_factory=list)     # steps with nothing after (locally)

    def predecessors(self, i: int) -> list[int]:
        return sorted(a for a, b in self.edges if b == i)

    def ops(self) -> list[str]:
        return [s.op for s in self.steps]

    def before(self, i: int, j: int) -> bool:
        """True if step i must precede step j (transitively)."""
        succ: dict[int, list[int]] = {}
        for a, b in self.edges:
            succ.setdefault(a, []).append(b)
        todo, seen = [i], set()
        while todo:
            n = todo.pop()
            for m in succ.get(n, ()):
                if m == j:
                    return True
                if m not in seen:
                    seen.add(m)
                    todo.append(m)
        return False


class PlanningFailed(Exception):
    """No method decomposes the task (or the expansion budget ran out)."""


Operator = Callable[..., dict[str, Any] | None]
MethodFn = Callable[..., Any]


class Domain:
    """Operators (primitive tasks) and methods (compound tasks)."""

    def __init__(self, name: str):
        self.name = name
        self.operators: dict[str, Operator] = {}
        self.methods: dict[str, list[tuple[str, MethodFn]]] = {}

    def operator(self, name: str):
        """Decorator: ``fn(ctx, *args) -> fields | None`` (None: not applicable)."""
        def deco(fn):
            self.operators[name] = fn
            return fn
        return deco

    def method(self, task: str, name: str | None = None):
        """Decorator: ``fn(ctx, *args) -> spec | None``; methods are tried in
        declaration order.  A method may also be a generator yielding several
        alternative specs."""
        def deco(fn):
            self.methods.setdefault(task, []).append((name or fn.__name__, fn))
            return fn
        return deco


class Planner:
    def __init__(self, domain: Domain, max_expansions: int = 10_000):
        self.domain = domain
        self.max_expansions = max_expansions
        self.expansions = 0

    def plan(self, ctx: Any, task: tuple | Seq | Par) -> Network:
        """The first network for ``task``; raises :class:`PlanningFailed`."""
        self.expansions = 0
        for net in self._expand(ctx, task):
            return net
        raise PlanningFailed(f"no decomposition of {task!r}")

    def alternatives(self, ctx: Any, task) -> Iterator[Network]:
        """Every network for ``task``, in preference order (lazily)."""
        self.expansions = 0
        yield from self._expand(ctx, task)

    # -- expansion ----------------------------------------------------------
    def _tick(self) -> None:
        self.expansions += 1
        if self.expansions > self.max_expansions:
            raise PlanningFailed(f"expansion budget of {self.max_expansions} exhausted")

    def _expand(self, ctx, spec) -> Iterator[Network]:
        if isinstance(spec, Seq):
            yield from self._combine(ctx, list(spec), ordered=True)
        elif isinstance(spec, Par):
            yield from self._combine(ctx, list(spec), ordered=False)
        elif spec is None or spec == ():
            yield Network()
        elif isinstance(spec, tuple) and spec and isinstance(spec[0], str):
            yield from self._expand_task(ctx, spec)
        else:
            raise TypeError(f"not a task or network spec: {spec!r}")

    def _expand_task(self, ctx, task: tuple) -> Iterator[Network]:
        self._tick()
        name, args = task[0], task[1:]
        op = self.domain.operators.get(name)
        if op is not None:
            fields = op(ctx, *args)
            if fields is not None:
                yield Network([Step(name, fields)], set(), [0], [0])
            return
        methods = self.domain.methods.get(name)
        if methods is None:
            raise PlanningFailed(f"domain {self.domain.name} has no operator or method "
                                 f"for {name!r}")
        for _mname, fn in methods:
            result = fn(ctx, *args)
            specs = result if isinstance(result, Iterator) else (result,)
            for spec in specs:
                if spec is None:
                    continue
                yield from self._expand(ctx, spec)

    def _combine(self, ctx, parts: list, ordered: bool) -> Iterator[Network]:
        if not parts:
            yield Network()
            return
        for head in self._expand(ctx, parts[0]):
            for tail in self._combine(ctx, parts[1:], ordered):
                yield _join(head, tail, ordered)


def _join(a: Network, b: Network, ordered: bool) -> Network:
    if not a.steps:
        return b
    if not b.steps:
        return a
    off = len(a.steps)
    steps = a.steps + b.steps
    edges = set(a.edges) | {(x + off, y + off) for x, y in b.edges}
    if ordered:
        edges |= {(s, t + off) for s in a.sinks for t in b.sources}
        return Network(steps, edges, list(a.sources), [t + off for t in b.sinks])
    return Network(steps, edges, a.sources + [t + off for t in b.sources],
                   a.sinks + [t + off for t in b.sinks])
