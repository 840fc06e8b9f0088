"""The ``subtree`` node: another tree file, included with parameters and
blackboard remapping.

Each instance gets its own blackboard scope (``/<instance name>/``, nested
for subtrees of subtrees), so two instances of one file never share keys.
``params:`` fill the file's declared ``params`` ($param.NAME); ``pass:``
fills them from the caller's parameters or task fields of the same name (a
list of names, or ``all``: every one the caller has); ``remap:``
maps keys of the subtree to keys of the caller (``target: $bb.goal``);
``autoremap: true`` maps every key of the subtree to the caller's key of the
same name.  The keys the file declares under ``outputs:`` are written to
the caller's keys of the same name unless ``remap:`` names others.  Keys
written with a leading ``/`` are absolute and shared.
The loader resolves all of this when the tree loads; at run time a subtree
is a pass-through node named after its instance.
"""
from __future__ import annotations

import py_trees

from .ports import Input
from .registry import DEFAULT, Slot, structural


class Subtree(py_trees.decorators.PassThrough):
    """Marks where an included file starts (for display and tick logs)."""


DEFAULT.register(structural(
    "subtree", "subtree", "Include another tree file as one node, with parameters, outputs and remapped keys.\n\n"
    + __doc__.split("\n\n", 1)[1],
    (Input(str, "the tree file, relative to this file (or on the search path)", constant=True, name="file"),
     Input(dict, "values for the subtree's declared params", required=False, name="params"),
     Input(object, "params passed on by name from the caller's own $param or $task: a list of names, or all",
           required=False, constant=True, name="pass"),
     Input(dict, "subtree key -> $bb.KEY of the caller", required=False, name="remap"),
     Input(bool, "map every key of the subtree to the caller's key of the same name", default=False,
           constant=True, name="autoremap")),
    (Slot("root", required=False, doc="(filled by the loader: the included tree)"),),
    lambda spec, slots, ctx: Subtree(spec.name, slots["root"][0])))
