"""Where a :class:`~.state.ViewState` gets its messages besides a running game's watch.

- :class:`Playback`: an MCAP recording (``rll-bt sim|agent|teamserver
  --record``) played back on its own clock, ``speed`` times real time, with
  pause and seek (seeking back starts the state over and feeds it up to there);
- :class:`FoxgloveSource`: a live Foxglove WebSocket server (``--live`` of
  ``rll-bt sim``, ``agent`` or ``teamserver``) followed as a client: it
  subscribes to the channels the page shows and decodes them with the
  schemas the server advertises (protobuf through ``mcap-protobuf-support``,
  JSON), so the page shows a game played by another process.

Both feed only the topics the page draws (:func:`shown`): no laser scans
or camera frames.
"""
from __future__ import annotations

import base64
import json
import re
import struct
import threading
import time
from pathlib import Path

from .state import ViewState

_SHOWN = re.compile(r"^(/robot\d+/(pose|true_pose|tree|tree/structure)|/game/(sample|stations|task|event|result)"
                    r"|/[a-z0-9_]+/public/(GameState|OrderInfo)|/refbox/(public|cyan|magenta)/MachineInfo)$")


def shown(topic: str) -> bool:
    """Whether the page draws anything of ``topic``."""
    return bool(_SHOWN.match(topic))


#: s a subscription waits after its channel's advertisement (see FoxgloveSource._control)
SUBSCRIBE_DELAY = 0.02
MAX_RETRIES = 5


class SourceError(ValueError):
    """A recording or live server that cannot be followed."""


def read_recording(path: str | Path) -> tuple[dict, list[tuple[float, str, object]]]:
    """The ``rll-bt`` metadata of a recording and its shown messages: ``(t, topic, value)`` in time order."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    from ..replay import JsonDecoderFactory
    try:
        fh = open(path, "rb")  # noqa: SIM115 - closed below
    except OSError as exc:
        raise SourceError(f"cannot open: {exc.strerror or exc}") from None
    out = []
    with fh:
        try:
            reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
            meta = next((dict(m.metadata) for m in reader.iter_metadata() if m.name == "rll-bt"), None)
            if meta is None:
                raise SourceError("no rll-bt metadata: not a recording of rll-bt")
            base = int(meta.get("base_ns", 0))
            summary = reader.get_summary()
            topics = [c.topic for c in summary.channels.values() if shown(c.topic)] if summary else None
            for _s, ch, msg, value in reader.iter_decoded_messages(topics=topics, log_time_order=True):
                if shown(ch.topic):
                    out.append(((msg.log_time - base) / 1e9, ch.topic, value))
        except McapError as exc:
            raise SourceError(f"not a readable MCAP file: {exc}") from None
    return meta, out


class Playback:
    """Plays ``messages`` (``(t, topic, value)``, in time order) into ``state``,
    ``speed`` times real time, from a thread (:meth:`start`)."""

    def __init__(self, state: ViewState, messages: list, *, speed: float = 1.0, playing: bool = True):
        self.state = state
        self.messages = messages
        self.start_t = messages[0][0] if messages else 0.0
        self.end_t = messages[-1][0] if messages else 0.0
        self.speed = float(speed)
        self.playing = playing
        self.t = self.start_t
        self._i = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._feed_to(self.start_t)                # the first moment shows before play
        self._publish()

    def _publish(self) -> None:
        self.state.put("playback", {"t": round(self.t, 2), "start": self.start_t, "end": self.end_t,
                                    "speed": self.speed, "playing": self.playing})

    def _feed_to(self, t: float) -> None:
        msgs, i = self.messages, self._i
        while i < len(msgs) and msgs[i][0] <= t:
            self.state.feed(msgs[i][1], msgs[i][0], msgs[i][2])
            i += 1
        self._i = i
        self.t = t

    def seek(self, t: float) -> None:
        with self._lock:
            t = min(max(float(t), self.start_t), self.end_t)
            if t < self.t:
                self.state.reset()
                self._i = 0
            self._feed_to(t)
            self._publish()

    def control(self, cmd: dict) -> dict:
        """``POST /control`` (see :mod:`.server`)."""
        op = cmd.get("op")
        if op == "play":
            self.playing = True
            if self.t >= self.end_t:
                self.seek(self.start_t)
        elif op == "pause":
            self.playing = False
        elif op == "seek":
            self.seek(float(cmd["t"]))
        elif op == "speed":
            speed = float(cmd["speed"])
            if not 0 < speed <= 1000:
                raise ValueError(f"speed must be in (0, 1000], not {speed}")
            self.speed = speed
        else:
            raise ValueError(f"unknown op {op!r} (play, pause, seek, speed)")
        with self._lock:
            self._publish()
        return {"t": self.t, "speed": self.speed, "playing": self.playing}

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="rll-bt view playback", daemon=True)
        self._thread.start()

    def _run(self, step: float = 0.05) -> None:
        last = time.monotonic()
        while not self._stop.wait(step):
            now = time.monotonic()
            dt, last = now - last, now
            if not self.playing:
                continue
            with self._lock:
                t = min(self.t + dt * self.speed, self.end_t)
                self._feed_to(t)
                if t >= self.end_t:
                    self.playing = False
                self._publish()

    @property
    def done(self) -> bool:
        return self._i >= len(self.messages)

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2)


class FoxgloveSource:
    """Follows the Foxglove WebSocket server at ``url`` into ``state`` from a thread.

    :attr:`connected` is set once the server's info arrived; :attr:`error`
    holds why the connection ended (None while it runs or after :meth:`close`)."""

    SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")

    def __init__(self, state: ViewState, url: str, *, open_timeout: float = 5.0):
        self.state = state
        self.url = url
        self.open_timeout = open_timeout
        self.connected = threading.Event()
        self.server_name: str | None = None
        self.error: str | None = None
        self.messages = 0
        self.retries: dict[int, int] = {}       # channel id -> subscriptions refused as unknown
        self._stop = threading.Event()
        self._ws = None
        self._subs: dict[int, tuple[str, object]] = {}
        self._sub_of: dict[int, int] = {}            # channel id -> subscription id
        self._pending: dict[int, tuple[float, int]] = {}   # channel id -> (when to subscribe, tries)
        self._next_sub = 1
        self._t0: int | None = None
        self._thread = threading.Thread(target=self._run, name="rll-bt view foxglove", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        from websockets.exceptions import ConnectionClosed
        from websockets.sync.client import connect
        try:
            with connect(self.url, subprotocols=list(self.SUBPROTOCOLS), open_timeout=self.open_timeout,
                         max_size=None) as ws:
                self._ws = ws
                while not self._stop.is_set():
                    self._subscribe_due(ws)
                    try:
                        m = ws.recv(timeout=0.02 if self._pending else 0.2)
                    except TimeoutError:
                        continue
                    if isinstance(m, str):
                        self._control(ws, json.loads(m))
                    elif m and m[0] == 1:
                        self._data(m)
        except ConnectionClosed:
            if not self._stop.is_set():
                self.error = "the live server closed the connection (the game ended?)"
        except (OSError, TimeoutError) as exc:
            self.error = f"cannot connect to {self.url}: {exc}"
        except Exception as exc:          # a protocol this client does not speak
            self.error = f"{type(exc).__name__}: {exc}"
        finally:
            self.connected.set()

    def _control(self, ws, op: dict) -> None:
        kind = op.get("op")
        if kind == "serverInfo":
            self.server_name = op.get("name", "")
            m = re.search(r"rcll20\d\d", self.server_name or "")
            self.state.set_meta(source="foxglove", url=self.url, name=self.server_name,
                                **({"profile": m.group(0)} if m else {}))
            self.connected.set()
        elif kind == "advertise":
            for ch in op.get("channels", []):
                if not shown(ch.get("topic", "")):
                    continue
                decode = _decoder(ch)
                if decode is None:
                    continue
                sid, self._next_sub = self._next_sub, self._next_sub + 1
                self._subs[sid] = (ch["topic"], decode)
                self._sub_of[ch["id"]] = sid
                self._pending[ch["id"]] = (time.monotonic() + SUBSCRIBE_DELAY, 0)
        elif kind == "status":
            # foxglove-sdk (0.30 and its main branch) sends an advertisement before it files the
            # channel under the client: a subscription arriving in between is refused with
            # "Unknown channel ID: N".  The channel is there a moment later, so ask again.
            m = re.fullmatch(r"Unknown channel ID: (\d+)", str(op.get("message", "")))
            if m and int(m.group(1)) in self._sub_of:
                cid = int(m.group(1))
                tries = self.retries.get(cid, 0) + 1
                self.retries[cid] = tries
                if tries <= MAX_RETRIES:
                    self._pending[cid] = (time.monotonic() + SUBSCRIBE_DELAY * 2 ** tries, tries)
        elif kind == "unadvertise":
            for cid in op.get("channelIds", []):
                self._pending.pop(cid, None)
                self._subs.pop(self._sub_of.pop(cid, -1), None)

    def _subscribe_due(self, ws) -> None:
        now = time.monotonic()
        due = [cid for cid, (when, _tries) in self._pending.items() if when <= now]
        if due:
            ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": self._sub_of[cid], "channelId": cid} for cid in due]}))
            for cid in due:
                del self._pending[cid]

    def _data(self, m: bytes) -> None:
        sid, ns = struct.unpack_from("<IQ", m, 1)
        sub = self._subs.get(sid)
        if sub is None:
            return
        topic, decode = sub
        if self._t0 is None:
            self._t0 = ns
        try:
            value = decode(bytes(m[13:]))
        except Exception:
            return
        self.messages += 1
        self.state.feed(topic, (ns - self._t0) / 1e9, value)

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(3)


def _decoder(ch: dict):
    """A function decoding a channel's messages, from its advertised schema (None: not decodable)."""
    enc = ch.get("encoding")
    if enc == "json":
        return lambda data: json.loads(data)
    if enc == "protobuf":
        from mcap.records import Schema
        from mcap_protobuf.decoder import DecoderFactory
        try:
            data = base64.b64decode(ch.get("schema", ""))
            return DecoderFactory().decoder_for("protobuf", Schema(id=1, name=ch["schemaName"], encoding="protobuf",
                                                                   data=data))
        except Exception:
            return None
    return None


__all__ = ["FoxgloveSource", "Playback", "SourceError", "read_recording", "shown"]
