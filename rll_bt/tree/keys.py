"""The blackboard keys of a tree being loaded: who writes, who reads, who
declares them, and the checks made once the whole tree is read.

- every key has one type: its writers (output ports, ``set_blackboard``
  literals, ``blackboard:`` and ``outputs:`` declarations) agree, and the
  input ports that read it accept it;
- every key read is written or declared somewhere in the tree (or is one of
  the engine's error keys, ``/error/code``, ``/error/message``,
  ``/error/node``): a read nobody writes is a misspelt or forgotten key;
- every declared output is written by its file.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .blackboard import ERROR_CODE_KEY, ERROR_MESSAGE_KEY, ERROR_NODE_KEY
from .errors import Loc, did_you_mean
from .files import Report
from .porttypes import PortType

#: keys the engine writes (``fail_with_error``, ``recovery``, skills' errors)
ENGINE_KEYS = {ERROR_CODE_KEY: "the engine (the error code of the step that failed)",
               ERROR_MESSAGE_KEY: "the engine (the error message)",
               ERROR_NODE_KEY: "the engine (the node that wrote the error)"}


@dataclass(frozen=True)
class Use:
    """One read or write of a key: its type, where, and who (for messages)."""
    key: str
    ptype: PortType
    loc: Loc
    what: str


@dataclass
class KeyBook:
    reads: list[Use] = field(default_factory=list)
    writes: list[Use] = field(default_factory=list)
    #: declared outputs: absolute key -> the declaration's use (type, place)
    outputs: dict[str, Use] = field(default_factory=dict)

    def read(self, key: str, ptype: PortType, loc: Loc, what: str) -> None:
        self.reads.append(Use(key, ptype, loc, what))

    def write(self, key: str, ptype: PortType, loc: Loc, what: str) -> None:
        self.writes.append(Use(key, ptype, loc, what))

    def retype(self, key: str, ptype: PortType, loc: Loc, what: str) -> None:
        """Replace the write at ``loc`` to ``key`` by one of a better-known type."""
        self.writes[:] = [w for w in self.writes if not (w.key == key and w.loc == loc)]
        self.write(key, ptype, loc, what)

    def declare_output(self, key: str, ptype: PortType, loc: Loc, what: str) -> None:
        self.outputs.setdefault(key, Use(key, ptype, loc, what))

    def mark(self) -> int:
        """A position in the writes, for :meth:`written_since`."""
        return len(self.writes)

    def written_since(self, mark: int, key: str) -> bool:
        return any(w.key == key for w in self.writes[mark:])

    def types(self) -> dict[str, PortType]:
        """Each written or declared key's type (the first declaration or writer)."""
        out = {k: u.ptype for k, u in self.outputs.items()}
        for w in self.writes:
            out.setdefault(w.key, w.ptype)
        return out

    def check(self, report: Report) -> None:
        writers: dict[str, Use] = {}
        for use in list(self.outputs.values()) + self.writes:
            if use.ptype.name == "any":
                continue
            first = writers.get(use.key)
            if first is None:
                writers[use.key] = use
            elif not (first.ptype.accepts(use.ptype) or use.ptype.accepts(first.ptype)):
                report(use.loc, f"{use.what} writes {use.ptype.name} to {use.key}, which {first.what} at {first.loc} "
                       f"writes as {first.ptype.name}", "use one type per blackboard key, or another key")
        written = {w.key for w in self.writes} | set(self.outputs)
        for use in self.reads:
            w = writers.get(use.key)
            if w is not None and not use.ptype.accepts(w.ptype):
                report(use.loc, f"{use.what} expects {use.ptype.name} but blackboard key {use.key} holds "
                       f"{w.ptype.name} (written by {w.what} at {w.loc})",
                       "bind a key of the right type, or convert the value")
            if use.key not in written and use.key not in ENGINE_KEYS:
                near = did_you_mean(use.key, sorted(written | set(ENGINE_KEYS)), "keys")
                report(use.loc, f"{use.what} reads blackboard key {use.key}, which nothing in the tree writes or "
                       "declares", (near + "; " if near.startswith("did you mean") else "")
                       + "declare a key written from outside the tree under `blackboard:`")
