"""A message log: frames or messages a transport carried, decoded, as JSON lines.

A game taps its bus with :meth:`MessageLog.tap` (every frame); a process
on real sockets records what one of its transports sent and received with
:meth:`MessageLog.record` (``rll-bt refbox sim --message-log``, the team
server of ``rll-bt sim --processes``, whose lines :mod:`games.teamlog`
merges).  One line per frame carried::

    {"t": 312.45, "channel": "cyan", "from": "R2", "type": "BeaconSignal", "msg": {...}}

``t`` is the log's clock (s; a game's simulation clock); ``channel`` the
bus channel or stream address; ``msg`` the protobuf JSON mapping (original field names, enums by
name).  Frames of the team channels and the team-server link are decrypted
with the team key; a frame that cannot be decoded is logged with ``type``
null and the ``error`` cause.

Size: a whole 2016 game writes about 8 MB (24 000 lines), nine tenths of it
messages that repeat on a timer (:data:`PERIODIC`: beacons, heartbeats,
robot statuses, the refbox's broadcasts).  A log holds everything until it
reaches ``limit`` bytes (:data:`LOG_LIMIT`, 64 MB, well over a game's).
From then on the periodic messages are left out and counted; every other
message (the tasks, their results and acknowledgements, the robots'
hellos and observations, the reports and machine instructions to the
refbox) is still written, so the tasks the report reads from a log are all
there, and past the limit the log grows only with the work done.  A line
with ``type`` null and ``limit`` (``{"bytes", "left_out": {type: count}}``)
says where the leaving out began and, when the log is closed, how much it
left out.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import IO

from ..msgs import to_dict
from .codec import FrameCodec
from .registry import MessageRegistry
from .stats import DropStats


class _Counted(DropStats):
    """Drop counts without the warning: trying the plain codec on an encrypted
    frame (and back) is how the log finds the right one."""

    def add(self, cause: str, detail: str = "") -> None:
        with self._lock:
            self._counts[cause] = self._counts.get(cause, 0) + 1


class FrameDecoder:
    """Decodes tapped frames with the registry of their channel, plain or
    with the team key.  ``registries``: channel or address ->
    :class:`MessageRegistry` (``default`` for the rest); ``key``: the team
    key, or channel or address -> key (a game of two teams, each its own)."""

    def __init__(self, registries: dict[str, MessageRegistry], default: MessageRegistry,
                 key: str | dict[str, str] | None = None):
        self._codecs: dict[str, tuple[FrameCodec, FrameCodec | None]] = {}
        self._registries = registries
        self._default = default
        self._key = key

    def _codec(self, channel: str) -> tuple[FrameCodec, FrameCodec | None]:
        pair = self._codecs.get(channel)
        if pair is None:
            reg = self._registries.get(channel, self._default)
            key = self._key.get(channel) if isinstance(self._key, dict) else self._key
            keyed = FrameCodec(reg, key=key, stats=_Counted()) if key else None
            pair = self._codecs[channel] = (FrameCodec(reg, stats=_Counted()), keyed)
        return pair

    def decode(self, channel: str, frame: bytes):
        """(message, None) or (None, cause)."""
        plain, keyed = self._codec(channel)
        decoded, cause = plain.try_decode(frame)
        if decoded is None and keyed is not None:
            decoded, cause = keyed.try_decode(frame)
        return (decoded.msg, None) if decoded is not None else (None, cause)


#: bytes a log holds before it leaves out the periodic messages
LOG_LIMIT = 64 << 20
#: messages sent again and again on a timer, whatever happens: left out past the limit
PERIODIC = frozenset({"BeaconSignal", "Heartbeat", "RobotStatus", "GamePhase", "GameState", "MachineInfo",
                      "OrderInfo", "RingInfo", "RobotInfo", "ExplorationInfo", "MachineMap", "VersionInfo",
                      "MachineReportInfo", "GameInfo"})


class MessageLog(FrameDecoder):
    """Writes tapped frames, decoded, as JSON lines (see the module doc).

    ``key``: the team key; ``line_buffered``: every line reaches the file at
    once (a process that may be killed); ``limit``: bytes after which the
    :data:`PERIODIC` messages (and undecoded frames) are left out (None: never).
    """

    def __init__(self, path: str | Path, clock, registries: dict[str, MessageRegistry],
                 default: MessageRegistry, key: str | None = None, line_buffered: bool = False,
                 limit: int | None = LOG_LIMIT):
        super().__init__(registries, default, key)
        self.path = Path(path)
        self.clock = clock
        self._fh: IO[str] | None = open(self.path, "w", encoding="utf-8",  # noqa: SIM115 - closed by close()
                                        buffering=1 if line_buffered else -1)
        self.lines = 0
        self.undecoded = 0
        self.types: dict[str, int] = {}
        self.limit = limit
        self.bytes = 0
        self.left_out: dict[str, int] = {}

    def tap(self, channel: str, source, frame: bytes) -> None:
        """A :meth:`rll_bt.comm.Bus.tap` callback."""
        if self._fh is None:
            return
        msg, cause = self.decode(channel, frame)
        if msg is None:
            self.undecoded += 1
            self._write({"t": round(self.clock.now(), 4), "channel": channel, "from": str(source),
                         "type": None, "error": cause, "bytes": len(frame)})
        else:
            self.record(channel, source, msg)

    def record(self, channel: str, source, msg) -> None:
        """Log a message that is already decoded (a transport's tap)."""
        if self._fh is None:
            return
        name = msg.DESCRIPTOR.name
        self.types[name] = self.types.get(name, 0) + 1
        self._write({"t": round(self.clock.now(), 4), "channel": channel, "from": str(source), "type": name,
                     "msg": to_dict(msg)})

    def _write(self, entry: dict) -> None:
        line = json.dumps(entry, separators=(",", ":")) + "\n"
        if self.limit is not None and self.bytes + len(line) > self.limit and entry["type"] in PERIODIC | {None}:
            kind = entry["type"] or "undecoded"
            if not self.left_out:
                self._mark()
            self.left_out[kind] = self.left_out.get(kind, 0) + 1
            return
        self._fh.write(line)
        self.bytes += len(line.encode("utf-8"))
        self.lines += 1

    def _mark(self) -> None:
        """The line that says what the limit left out (so far)."""
        line = json.dumps({"t": round(self.clock.now(), 4), "channel": "log", "from": "log", "type": None,
                           "limit": {"bytes": self.limit, "left_out": dict(self.left_out)}},
                          separators=(",", ":")) + "\n"
        self._fh.write(line)
        self.bytes += len(line)
        self.lines += 1

    def close(self) -> None:
        if self._fh is not None:
            if self.left_out:
                self._mark()
            self._fh.close()
            self._fh = None
