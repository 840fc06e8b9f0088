"""Read a game recording back: ``rll-bt replay game.mcap``.

:func:`read` walks the MCAP file with the ``mcap`` reader (protobuf
messages decoded by ``mcap-protobuf-support``, JSON ones by
:class:`JsonDecoderFactory`) and rebuilds the game's
:class:`~games.recorder.Recording` from the ``/game/sample``,
``/game/task`` and ``/game/event`` topics, the stations from
``/game/stations`` and the end of the game from ``/game/result``, so the
report's table and pictures are drawn again exactly as the game drew them.
A recording cut short (a game that was killed) still gives everything up to
its last message.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from rll_bt.backend import Pose2D
from rll_bt.contracts import Award, Delivery, GameStatus, StationTruth

from .recorder import Recording


class RecordingError(ValueError):
    """Not an rll-bt recording (or not an MCAP file at all)."""


class JsonDecoderFactory:
    """Decodes ``json`` messages for :func:`mcap.reader.make_reader`."""

    def decoder_for(self, message_encoding: str, schema):
        if message_encoding != "json":
            return None
        return lambda data: json.loads(data)


@dataclass
class Replay:
    path: Path
    meta: dict[str, str]
    base_ns: int
    topics: dict[str, dict] = field(default_factory=dict)      # topic -> {schema, encoding, count}
    recording: Recording = field(default_factory=Recording)
    stations: dict[str, StationTruth] = field(default_factory=dict)
    result: dict | None = None
    start: float = 0.0
    end: float = 0.0

    @property
    def sim_time(self) -> float:
        return float(self.result["sim_time"]) if self.result else self.end

    def options(self):
        """The :class:`~games.options.GameOptions` the game was played with (as recorded)."""
        from .options import GameOptions
        m = self.meta

        def num(k):
            return float(m[k]) if m.get(k) not in (None, "None", "") else None
        return GameOptions(profile=m.get("profile", "rcll2016"), seed=int(m.get("seed", 0)),
                           robots=int(m.get("robots", 3)), strategy=m.get("strategy", "algorithm1"),
                           perception=m.get("perception", "oracle"), baseline=m.get("baseline") == "True",
                           until=m.get("until", "end"), setup=num("setup"), exploration=num("exploration"),
                           production=num("production"))

    def game_result(self):
        """A :class:`~games.lockstep.GameResult` as far as the recording tells it."""
        from .lockstep import GameResult
        r = self.result or {}
        last = self.recording.samples[-1] if self.recording.samples else {"phase": "?", "game_time": 0.0}
        status = GameStatus(**r["status"]) if "status" in r else GameStatus(last["phase"], "?", last["game_time"],
                                                                            None, {})
        return GameResult(finished=bool(r.get("finished", False)), status=status, recording=self.recording,
                          awards=[Award(**a) for a in r.get("awards", [])],
                          deliveries=[Delivery(**d) for d in r.get("deliveries", [])],
                          snapshot={"restarts": r.get("team_server_restarts", 0)}, stations=self.stations,
                          orders=r.get("orders", []), collisions=int(r.get("collisions", 0)),
                          sim_time=self.sim_time, collision_log=[tuple(c) for c in r.get("collision_log", [])],
                          messages=int(r.get("messages", 0)), tally=_tally(r))


def _tally(result: dict) -> dict:
    """The team's tally back from a report's ``stations_broken`` and ``referee``."""
    from rll_bt.contracts import Tally
    if "stations_broken" not in result:
        return {}
    return {result.get("team", "CYAN"): Tally(dict(result["stations_broken"].get("by_cause", {})),
                                              dict(result.get("referee", {}).get("calls", {})))}


def read(path: str | Path) -> Replay:
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory
    p = Path(path)
    try:
        fh = p.open("rb")
    except OSError as exc:
        raise RecordingError(f"cannot open: {exc.strerror or exc}") from None
    with fh:
        try:
            reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
            meta = next((m.metadata for m in reader.iter_metadata() if m.name == "rll-bt"), None)
            if meta is None:
                raise RecordingError("no rll-bt metadata: not a recording of rll-bt")
            rep = Replay(p, dict(meta), int(meta.get("base_ns", 0)))
            rep.recording.team = meta.get("team", "CYAN")
            first = None
            for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
                t = (message.log_time - rep.base_ns) / 1e9
                first = t if first is None else first
                rep.end = max(rep.end, t)
                info = rep.topics.setdefault(channel.topic, {"schema": schema.name if schema else "",
                                                             "encoding": channel.message_encoding, "count": 0})
                info["count"] += 1
                if channel.topic.startswith("/game/"):
                    _game(rep, channel.topic[6:], decoded)
            rep.start = first or 0.0
        except McapError as exc:
            raise RecordingError(f"not a readable MCAP file: {exc}") from None
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, RecordingError):
                raise
            raise RecordingError(f"damaged recording: {type(exc).__name__}: {exc}") from None
    return rep


def _game(rep: Replay, kind: str, d: Any) -> None:
    rec = rep.recording
    if kind == "sample":
        if not rec.phases or rec.phases[-1][1] != d["phase"]:
            rec.phases.append((d["now"], d["phase"]))
        rec.samples.append({k: d[k] for k in ("t", "phase", "game_time", "points")})
        for n, pt in d["paths"].items():
            rec.paths.setdefault(int(n), []).append(tuple(pt))
        for name, ch in d["stations"].items():
            rec.stations.setdefault(name, []).append(tuple(ch))
        rec.exploration_started = d.get("exploration_started")
        rec.known_all_at = d.get("known_all_at")
        rec.known_all_game_time = d.get("known_all_game_time")
    elif kind == "task":
        d = dict(d)
        runs = rec.tasks.setdefault(int(d.pop("robot")), [])
        i = int(d.pop("index"))
        while len(runs) <= i:
            runs.append({})
        runs[i] = d
    elif kind == "event":
        rec.events.append(dict(d))
    elif kind == "stations":
        rep.stations = {s["name"]: StationTruth(s["name"], s["team"], int(s["zone"]), int(s["rotation"]),
                                                Pose2D(*s["pose"]), s["state"], tuple(s["light"]))
                        for s in d["stations"]}
    elif kind == "result":
        rep.result = d


def summary_lines(rep: Replay) -> list[str]:
    """What the recording holds: topics, their schemas and message counts."""
    m = rep.meta
    total = sum(i["count"] for i in rep.topics.values())
    if m.get("kind", "sim") == "sim":
        what = f"{m.get('profile', '?')} seed {m.get('seed', '?')}, {rep.end - rep.start:.1f} s of sim time"
        cut = "" if rep.result else " (cut short: no /game/result)"
    else:                                    # an agent's or a team server's own recording
        what = f"{m.get('profile', '?')}, {rep.end - rep.start:.1f} s of wall time"
        cut = ""
    lines = [f"{rep.path}: {m.get('name', 'rll-bt')} recording, {what}, {total} messages on {len(rep.topics)} "
             f"topics{cut}", ""]
    width = max((len(t) for t in rep.topics), default=5)
    lines.append(f"{'topic':{width}}  {'messages':>8}  schema")
    for topic in sorted(rep.topics):
        info = rep.topics[topic]
        lines.append(f"{topic:{width}}  {info['count']:8d}  {info['schema']} ({info['encoding']})")
    return lines


def redraw(rep: Replay, out: str | Path) -> list[Path]:
    """The report's PNGs (field, timeline, score) drawn from the recording."""
    from .plots import draw_all
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    opts = rep.options()
    return draw_all(opts.rules, SimpleNamespace(recording=rep.recording, stations=rep.stations,
                                                sim_time=rep.sim_time), out)
