"""``rll-bt sim --processes --record game.mcap``: each process records its own
part and the game merges them on the game's clock.

- every agent process records itself (``rll-bt agent --record``): its pose
  estimate, scans, camera frames, detections and trees (:mod:`rll_bt.watch`),
  stamped in Unix time from the machine's monotonic clock;
- this process (the world's) records the robots' true poses and the field
  on the simulation clock (``world.mcap``);
- every message of the refbox channels and of the team-server link is in the
  game's ``messages.jsonl`` already (what the refbox process and the team
  server process sent and received, merged on the game's clock by
  :mod:`.teamlog`): they become the protobuf topics ``/<sender>/<channel>/<Type>``;
- the ``/game/...`` topics are written from the game's final recording, as
  lockstep writes them while it plays (:mod:`.watch`), so ``rll-bt replay``
  draws the report the game drew.

At the end :meth:`ProcessWatch.finish` writes one MCAP file with the
``mcap`` writer, every message on the game's clock (seconds since the game
started, as the report's): the world's part shifted by the game's start,
the agents' parts mapped from the wall clock through the pairs the world
took as it stepped (:class:`~games.teamlog.WallToSim`).  An agent's own
copies of link and refbox messages are left out (the team server's and the
refbox's logs hold them once).  A part cut short (a killed agent) gives
what it holds.
"""
from __future__ import annotations

import json
from pathlib import Path

from .watch import SAMPLE_SCHEMA, field_scene, result_record, station_record, topic_for

#: topic channel segments that carry link or refbox messages (recorded once, from messages.jsonl)
MESSAGE_CHANNELS = frozenset({"public", "cyan", "magenta", "link", "refbox", "stream"})


class ProcessWatch:
    """The world's part of a :class:`~games.processes.ProcessGame`'s recording (see the module doc)."""

    def __init__(self, game, path: Path, parts: Path):
        from rll_bt.watch.sink import Watch
        self.game = game
        self.path = Path(path)
        self.parts = Path(parts)
        self.parts.mkdir(parents=True, exist_ok=True)
        for old in self.parts.glob("*.mcap"):
            old.unlink()
        self.world_part = self.parts / "world.mcap"
        self.watch = Watch(record=self.world_part, clock=game.clock, name="rll-bt sim world")
        self.truth_period = 0.1
        self._next_truth = -1e18
        self._agent_parts: dict[int, int] = {}
        self._states: dict[str, str] = {}
        self.merged: dict[str, int] = {}

    def agent_part(self, number: int) -> Path:
        """Where the next agent process of robot ``number`` records itself."""
        k = self._agent_parts[number] = self._agent_parts.get(number, 0) + 1
        return self.parts / (f"agent{number}.mcap" if k == 1 else f"agent{number}-{k}.mcap")

    def stepped(self) -> None:
        """After a world step: true poses (10 a second), the field when a station changed."""
        g = self.game
        now = g.clock.now()
        if now >= self._next_truth - 1e-6:
            nxt = self._next_truth + self.truth_period
            self._next_truth = nxt if nxt > now else now + self.truth_period
            for n in g.robots:
                self.watch.pose(f"/robot{n}/true_pose", g.world.robot_pose("CYAN", n))
        stations = g.refbox.stations()
        states = {n: s.state for n, s in stations.items()}
        if states != self._states:
            self._states = states
            self.watch.scene("/field", field_scene(g.options.rules, stations))

    # -- the end ----------------------------------------------------------------------------------
    def finish(self, result, messages: Path | None, t0: float) -> Path:
        """Write the merged recording (``t0``: the simulation time the game started)."""
        self.watch.close()
        g = self.game
        o = g.options
        base_ns = self.watch.base_ns
        out = _Merged(self.path, base_ns, {
            "kind": "sim", "processes": "True", "team": "CYAN", "name": "rll-bt sim",
            **{k: getattr(o, k) for k in ("profile", "seed", "robots", "strategy", "perception", "baseline",
                                           "until", "setup", "exploration", "production")}})
        shift_ns = round(t0 * 1e9)
        _copy_part(out, self.world_part, lambda lt, _base: lt - shift_ns)
        to_sim = g.time_map
        for part in sorted(self.parts.glob("agent*.mcap")):
            _copy_part(out, part, lambda lt, base: out.seconds(to_sim((lt - base) / 1e9) - t0), keep=_own_topic)
        if messages is not None and messages.exists():
            _messages(out, messages, o.profile)
        _game_topics(out, result, o.rules)
        out.close()
        self.merged = out.counts
        for part in self.parts.glob("*.mcap"):
            part.unlink()
        try:
            self.parts.rmdir()
        except OSError:
            pass
        return self.path


def _own_topic(topic: str) -> bool:
    """An agent's own topic (pose, scan, tree ...), not its copy of a link or refbox message."""
    parts = topic.split("/")
    return not (len(parts) == 4 and parts[2] in MESSAGE_CHANNELS)


class _Merged:
    """An MCAP file written with the ``mcap`` writer, messages sorted by time at the end."""

    def __init__(self, path: Path, base_ns: int, meta: dict):
        self.path = path
        self.base_ns = base_ns
        self.meta = {"base_ns": str(base_ns), **{k: str(v) for k, v in meta.items()}}
        self._schemas: dict[tuple, int] = {}
        self._channels: dict[str, tuple] = {}      # topic -> (encoding, schema key)
        self._messages: list[tuple[int, str, bytes]] = []
        self.counts: dict[str, int] = {}

    def channel(self, topic: str, encoding: str, schema: tuple) -> None:
        self._channels.setdefault(topic, (encoding, schema))

    def add(self, topic: str, log_ns: int, data: bytes) -> None:
        self._messages.append((log_ns, topic, data))
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def seconds(self, t: float) -> int:
        return self.base_ns + round(t * 1e9)

    def close(self) -> None:
        from mcap.writer import Writer
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, "wb") as fh:
            w = Writer(fh)
            w.start(profile="", library="rll-bt")
            w.add_metadata("rll-bt", self.meta)
            ids: dict[str, int] = {}
            for topic, (encoding, schema) in self._channels.items():
                sid = self._schemas.get(schema)
                if sid is None:
                    sid = self._schemas[schema] = w.register_schema(*schema)
                ids[topic] = w.register_channel(topic, encoding, sid)
            self._messages.sort(key=lambda m: m[0])
            seq: dict[str, int] = {}
            for log_ns, topic, data in self._messages:
                seq[topic] = seq.get(topic, 0) + 1
                w.add_message(ids[topic], log_time=log_ns, data=data, publish_time=log_ns, sequence=seq[topic])
            w.finish()
        self._messages = []


def _records(path: Path):
    """(metadata, schemas, channels, messages) of an MCAP file, as far as it can be read."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    meta, schemas, channels, messages = {}, {}, {}, []
    try:
        with open(path, "rb") as fh:
            for rec in StreamReader(fh).records:
                if isinstance(rec, Message):
                    messages.append(rec)
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Metadata) and rec.name == "rll-bt":
                    meta = dict(rec.metadata)
    except (McapError, OSError, ValueError, EOFError):
        pass                               # cut short: what was written before
    return meta, schemas, channels, messages


def _copy_part(out: _Merged, path: Path, to_ns, keep=None) -> None:
    """The messages of ``path`` (topics ``keep`` takes), log times through
    ``to_ns(log_ns, base_ns)``; a message with a ``timestamp`` (Foxglove's
    well-known schemas) gets its new log time there too."""
    from mcap_protobuf.decoder import DecoderFactory
    meta, schemas, channels, messages = _records(path)
    base = int(meta.get("base_ns", 0))
    decoders: dict[int, object] = {}
    for m in messages:
        ch = channels.get(m.channel_id)
        if ch is None or (keep is not None and not keep(ch.topic)):
            continue
        s = schemas.get(ch.schema_id)
        out.channel(ch.topic, ch.message_encoding, (s.name, s.encoding, s.data) if s else ("", "", b""))
        lt = to_ns(m.log_time, base)
        data = m.data
        if s is not None and s.encoding == "protobuf" and s.name.startswith("foxglove."):
            if ch.id not in decoders:
                decoders[ch.id] = DecoderFactory().decoder_for("protobuf", s)
            msg = decoders[ch.id](data)
            if "timestamp" in msg.DESCRIPTOR.fields_by_name:
                msg.timestamp.FromNanoseconds(lt)
                data = msg.SerializeToString()
        out.add(ch.topic, lt, data)


def _messages(out: _Merged, path: Path, profile: str) -> None:
    """The game's message log as protobuf topics (lines that were not decoded are left out)."""
    from mcap_protobuf.schema import build_file_descriptor_set

    from rll_bt import msgs
    team, league = msgs.message_set("team"), msgs.message_set("rcll2025")
    default = msgs.message_set(profile)
    fds: dict[type, bytes] = {}
    with open(path, encoding="utf-8") as fh:
        for raw in fh:
            e = json.loads(raw)
            if not e.get("type"):
                continue
            # the robots' link: rll-bt's additions and the league's AgentTask / BeaconSignal (rcll2025)
            ms = (team if e["type"] in team.classes else league) if e["channel"] == "teamserver" else default
            msg = msgs.from_dict(ms, e["type"], e.get("msg") or {})
            cls = type(msg)
            if cls not in fds:
                fds[cls] = build_file_descriptor_set(cls).SerializeToString()
            topic = topic_for(e["channel"], e["from"], msg)
            out.channel(topic, "protobuf", (msg.DESCRIPTOR.full_name, "protobuf", fds[cls]))
            out.add(topic, out.seconds(e["t"]), msg.SerializeToString())


def _game_topics(out: _Merged, result, profile) -> None:
    """``/game/sample``, ``/game/task``, ``/game/event``, ``/game/stations``, ``/game/result``
    and ``/field`` from the game's final recording, in the lockstep recording's form."""
    schema = ("rllbt.GameSample", "jsonschema", json.dumps(SAMPLE_SCHEMA).encode())

    def put(kind: str, t: float, data: dict) -> None:
        topic = f"/game/{kind}"
        out.channel(topic, "json", schema)
        out.add(topic, out.seconds(t), json.dumps(data, separators=(",", ":"), default=str).encode())
    rec = result.recording
    final = {"exploration_started": rec.exploration_started, "known_all_at": rec.known_all_at,
             "known_all_game_time": rec.known_all_game_time}
    phases = list(rec.phases)
    changes: dict[float, dict] = {}
    for name, hist in rec.stations.items():
        for t, state in hist:
            changes.setdefault(t, {})[name] = (t, state)
    last_phase, k = None, 0
    for i, s in enumerate(rec.samples):
        now = s["t"]
        if s["phase"] != last_phase:
            while k < len(phases) and phases[k][1] != s["phase"]:
                k += 1
            if k < len(phases):
                now = phases[k][0]
                k += 1
            last_phase = s["phase"]
        paths = {n: list(pts[i]) for n, pts in rec.paths.items() if i < len(pts)}
        # a change goes with one sample: the game's last sample (made when it ends) may share the time
        # of the one before, and a change written with both was read back twice
        put("sample", s["t"], {**s, "now": now, "paths": paths, "stations": changes.pop(s["t"], {}), **final})
    for robot, runs in rec.tasks.items():
        for i, run in enumerate(runs):
            if run.get("end") is not None and run["end"] > run["start"]:
                put("task", run["start"], {"robot": robot, "index": i, **run, "end": None, "outcome": None})
            put("task", run["end"] if run.get("end") is not None else run["start"], {"robot": robot, "index": i, **run})
    for e in rec.events:
        put("event", e["t"], e)
    put("stations", result.sim_time, {"stations": [station_record(s) for s in result.stations.values()]})
    put("result", result.sim_time, result_record(result))


__all__ = ["ProcessWatch", "MESSAGE_CHANNELS"]
