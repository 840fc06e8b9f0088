"""Composite node types: sequences and selectors (memory named explicitly)
and parallel (policy and ``synchronise`` always explicit).

The behaviours are py_trees' own :class:`~py_trees.composites.Sequence`,
:class:`~py_trees.composites.Selector` and
:class:`~py_trees.composites.Parallel`.
"""
from __future__ import annotations

import py_trees
from py_trees.common import ParallelPolicy

from .errors import did_you_mean
from .ports import Input
from .registry import DEFAULT, Slot, structural

CHILDREN = Slot("children", many=True, doc="the child nodes, in order")


def _seq(memory: bool):
    def build(spec, slots, ctx):
        return py_trees.composites.Sequence(spec.name, memory=memory, children=slots["children"])
    return build


def _sel(memory: bool):
    def build(spec, slots, ctx):
        return py_trees.composites.Selector(spec.name, memory=memory, children=slots["children"])
    return build


for _name, _doc, _build in (
    ("sequence_with_memory", """
        Run the children in order until one fails.  With memory: a child that
        returned RUNNING is resumed on the next tick and the children before it
        are not ticked again.  SUCCESS when all succeed, FAILURE at the first
        failure.""", _seq(True)),
    ("reactive_sequence", """
        Run the children in order until one fails, starting again from the
        first child on every tick (no memory), so earlier conditions are
        re-checked while a later child runs.  A child that starts an action
        halts the running later child first.""", _seq(False)),
    ("selector_with_memory", """
        Try the children in order until one succeeds (a fallback).  With
        memory: a child that returned RUNNING is resumed on the next tick and
        higher priorities are not re-tried until it finishes.""", _sel(True)),
    ("reactive_selector", """
        Try the children in order until one succeeds, re-trying higher
        priorities on every tick (no memory): a higher-priority child that
        succeeds or runs preempts the running lower one, which is halted
        before the new one starts.""", _sel(False)),
):
    DEFAULT.register(structural(_name, "composite", _doc, (), (CHILDREN,), _build))


POLICIES = ("all", "one", "selected")


def _build_parallel(spec, slots, ctx):
    children = slots["children"]
    policy = spec.const("policy")
    if policy == "one":
        pol = ParallelPolicy.SuccessOnOne()
    elif policy == "all":
        pol = ParallelPolicy.SuccessOnAll(synchronise=spec.const("synchronise"))
    else:
        names = spec.const("selected")
        chosen = [c for c in children if c.name in names]
        pol = ParallelPolicy.SuccessOnSelected(children=chosen, synchronise=spec.const("synchronise"))
    return py_trees.composites.Parallel(spec.name, policy=pol, children=children)


def _check_parallel(spec, opts):
    policy = spec.const("policy")
    problems = []
    if policy in ("all", "selected") and "synchronise" not in spec.ports:
        problems.append((spec.loc, f"parallel with policy {policy!r} needs `synchronise: true|false` (no default)",
                         "true: children that succeeded are not ticked again until the policy is met; "
                         "false: every child is ticked on every tick"))
    if policy == "one" and "synchronise" in spec.ports:
        problems.append((opts.kloc("synchronise"), "policy 'one' has no `synchronise`",
                         "remove `synchronise:`; with 'one' the first success ends the parallel"))
    names = [c.name for c in spec.slots.get("children", [])]
    if policy == "selected":
        sel = spec.const("selected") or []
        if not sel:
            problems.append((spec.loc, "policy 'selected' needs `selected:` with child names",
                             "name the children with `name:` and list them: selected: [a, b]"))
        for n in sel:
            if n not in names:
                problems.append((opts.vloc("selected"), f"no child named {n!r} in this parallel",
                                 did_you_mean(n, names, "child names")))
            elif names.count(n) > 1:
                problems.append((opts.vloc("selected"), f"several children are named {n!r}",
                                 "give the selected children distinct names"))
    elif "selected" in spec.ports:
        problems.append((opts.kloc("selected"), f"`selected` is only for policy 'selected', not {policy!r}",
                         "remove it or use policy: selected"))
    return problems


DEFAULT.register(structural(
    "parallel", "composite", """
    Tick every child on every tick.  Any child's FAILURE fails the parallel.
    ``policy`` says when it succeeds: ``all`` children succeeded, ``one``
    child succeeded, or the ``selected`` children (by name) succeeded.
    ``synchronise`` (required for ``all`` and ``selected``, no default):
    whether children that already succeeded are skipped until the policy is
    met.  Children still running when the parallel finishes are halted.""",
    (Input(str, "when the parallel succeeds", choices=POLICIES, constant=True, name="policy"),
     Input(bool, "skip children that already succeeded", required=False, constant=True, name="synchronise"),
     Input(list[str], "names of the children that must succeed (policy: selected)", required=False,
           constant=True, name="selected")),
    (CHILDREN,), _build_parallel, _check_parallel))
