"""Channels for Foxglove: one :class:`Watch` writes to an MCAP file, to a
live Foxglove WebSocket server, or both, through the ``foxglove-sdk``.

    watch = Watch(record="game.mcap", live=8765, clock=sim_clock)
    watch.proto("/refbox/public/GameState", msg)           # any protobuf message, its schema with it
    watch.pose("/robot1/pose", Pose2D(1, 2, 0.5))          # foxglove.PoseInFrame in frame "field"
    watch.scan("/robot1/scan", scan, robot_pose)           # foxglove.LaserScan placed in the field
    watch.image("/robot1/camera", camera_image)            # foxglove.CompressedImage (JPEG)
    watch.json("/robot1/tree", {...}, schema={...})        # JSON with a JSON Schema
    watch.close()

Every channel is created on first use, with its schema: the project's own
messages as protobuf (the ``FileDescriptorSet`` of their .proto, built by
``mcap-protobuf-support``), Foxglove's well-known protobuf schemas for
poses, scans, images and 3D scenes, JSON Schema for the rest.  Message
times are ``base_ns`` plus the clock's seconds; ``base_ns`` (the wall time
the watch opened, unless given) is written as metadata ``rll-bt`` so a
reader gets the clock's seconds back (:func:`clock_seconds`).
"""
from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

from ..backend import Pose2D

FIELD = "field"
METADATA = "rll-bt"


class WatchUnavailable(RuntimeError):
    """foxglove-sdk or mcap is not installed."""


def _sdk():
    try:
        import foxglove
        from foxglove import channels, messages
    except ImportError as exc:      # pragma: no cover - the extra is part of the test install
        raise WatchUnavailable("recording and --live need the foxglove-sdk and mcap packages: "
                               "pip install 'rll-bt[watch]'") from exc
    return foxglove, channels, messages


def quaternion(theta: float):
    """A rotation about z as a foxglove Quaternion."""
    _, _, m = _sdk()
    return m.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2.0), w=math.cos(theta / 2.0))


class Watch:
    """See the module doc.  ``record``: an MCAP path; ``live``: a WebSocket
    port (0: any free one, see :attr:`port`); ``clock``: gives the seconds
    that message times count (``now()``); ``meta``: extra metadata;
    ``chunk_size``: bytes of messages written to the file at a time."""

    def __init__(self, *, record: str | Path | None = None, live: int | None = None, clock=None,
                 name: str = "rll-bt", base_ns: int | None = None, meta: dict | None = None,
                 host: str = "127.0.0.1", chunk_size: int = 1 << 20):
        fox, self._channels_mod, self._m = _sdk()
        self.clock = clock
        self.base_ns = time.time_ns() if base_ns is None else int(base_ns)
        self.context = fox.Context()
        self._channels: dict[str, Any] = {}
        self.counts: dict[str, int] = {}
        self.closed = False
        #: ``fn(topic, seconds, value)`` for every message: the value as given (a protobuf message,
        #: a dict, a Pose2D); a live view in the browser listens here
        self.listeners: list = []
        self.writer = None
        self.server = None
        self.path = Path(record) if record is not None else None
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            from foxglove.mcap import MCAPWriteOptions
            # one compression thread: up to 9 games share 2 cores; ``chunk_size``: what a killed
            # process loses at most (its file holds the chunks written before)
            opts = MCAPWriteOptions(chunk_size=int(chunk_size), compression_threads=0)
            self.writer = fox.open_mcap(str(self.path), allow_overwrite=True, context=self.context,
                                        writer_options=opts)
            self.writer.write_metadata(METADATA, {"base_ns": str(self.base_ns), "name": name,
                                                  **{k: str(v) for k, v in (meta or {}).items()}})
        if live is not None:
            self.server = fox.start_server(name=name, host=host, port=int(live), context=self.context)

    @property
    def port(self) -> int | None:
        """The live server's port."""
        return self.server.port if self.server is not None else None

    # -- time ------------------------------------------------------------------------
    def stamp(self, t: float | None = None) -> int:
        """Nanoseconds of clock time ``t`` (default: now)."""
        if t is None:
            t = self.clock.now() if self.clock is not None else 0.0
        return self.base_ns + round(t * 1e9)

    def _ts(self, ns: int):
        from foxglove.messages import Timestamp
        return Timestamp(sec=ns // 1_000_000_000, nsec=ns % 1_000_000_000)

    def _log(self, topic: str, channel, payload, ns: int, value=None) -> None:
        if self.closed:
            return
        channel.log(payload, log_time=ns)
        if self.listeners and value is not None:
            t = (ns - self.base_ns) / 1e9
            for fn in self.listeners:
                fn(topic, t, value)
        self.counts[topic] = self.counts.get(topic, 0) + 1

    # -- channels ----------------------------------------------------------------------
    def _well_known(self, topic: str, kind: str):
        ch = self._channels.get(topic)
        if ch is None and not self.closed:
            ch = self._channels[topic] = getattr(self._channels_mod, kind + "Channel")(topic, context=self.context)
        return ch

    def _proto_channel(self, topic: str, cls):
        import foxglove
        ch = self._channels.get(topic)
        if ch is None:
            from mcap_protobuf.schema import build_file_descriptor_set
            fds = build_file_descriptor_set(cls)
            schema = foxglove.Schema(name=cls.DESCRIPTOR.full_name, encoding="protobuf", data=fds.SerializeToString())
            ch = self._channels[topic] = foxglove.Channel(topic, message_encoding="protobuf", schema=schema,
                                                          context=self.context)
        return ch

    def _json_channel(self, topic: str, schema: dict | None):
        import foxglove
        ch = self._channels.get(topic)
        if ch is None:
            ch = self._channels[topic] = foxglove.Channel(topic, schema=schema or {"type": "object"},
                                                          context=self.context)
        return ch

    def declare(self, topic: str, kind: str, schema=None) -> None:
        """Create ``topic``'s channel before its first message: ``kind`` a Foxglove
        well-known schema ("PoseInFrame", "LaserScan", ...), "json" (``schema``: its JSON
        Schema) or "proto" (``schema``: the message class).  A live client that connects
        later is told of it as it connects (foxglove-sdk files a channel created while a
        client is connected only after advertising it, so a quick subscription can miss it)."""
        if self.closed:
            return
        if kind == "json":
            self._json_channel(topic, schema)
        elif kind == "proto":
            self._proto_channel(topic, schema)
        else:
            self._well_known(topic, kind)

    def proto(self, topic: str, msg, t: float | None = None) -> None:
        """A protobuf message, with its own schema."""
        if self.closed:
            return
        self._log(topic, self._proto_channel(topic, type(msg)), msg.SerializeToString(), self.stamp(t), msg)

    def json(self, topic: str, data: dict, t: float | None = None, schema: dict | None = None) -> None:
        """A JSON object (``schema``: its JSON Schema, given on the first message of a topic)."""
        if self.closed:
            return
        payload = json.dumps(data, separators=(",", ":"), default=str).encode()
        self._log(topic, self._json_channel(topic, schema), payload, self.stamp(t), data)

    def pose(self, topic: str, pose: Pose2D, t: float | None = None, frame: str = FIELD, z: float = 0.0) -> None:
        """A field pose as ``foxglove.PoseInFrame``."""
        m = self._m
        ns = self.stamp(t)
        msg = m.PoseInFrame(timestamp=self._ts(ns), frame_id=frame,
                            pose=m.Pose(position=m.Vector3(x=pose.x, y=pose.y, z=z),
                                        orientation=quaternion(pose.theta)))
        self._log(topic, self._well_known(topic, "PoseInFrame"), msg, ns, pose)

    def scan(self, topic: str, scan, robot: Pose2D | None, t: float | None = None, frame: str = FIELD) -> None:
        """A :class:`~rll_bt.backend.LaserScan` as ``foxglove.LaserScan``: placed in the
        field at ``robot`` composed with the laser's mount (in the robot frame without a pose)."""
        m = self._m
        ns = self.stamp(t if t is not None else getattr(scan, "stamp", None))
        origin = robot.compose(scan.mount) if robot is not None else scan.mount
        n = len(scan.ranges)
        ranges = [float(r) if math.isfinite(r) else float("inf") for r in scan.ranges]
        msg = m.LaserScan(timestamp=self._ts(ns), frame_id=frame if robot is not None else "robot",
                          pose=m.Pose(position=m.Vector3(x=origin.x, y=origin.y, z=0.3),
                                      orientation=quaternion(origin.theta)),
                          start_angle=float(scan.angle_min),
                          end_angle=float(scan.angle_min + scan.angle_increment * max(n - 1, 0)),
                          ranges=ranges)
        self._log(topic, self._well_known(topic, "LaserScan"), msg, ns)

    def image(self, topic: str, image, t: float | None = None, quality: int = 80) -> bool:
        """A :class:`~rll_bt.backend.CameraImage` as JPEG ``foxglove.CompressedImage``."""
        import cv2
        ok, buf = cv2.imencode(".jpg", image.image, [int(cv2.IMWRITE_JPEG_QUALITY), quality])
        if not ok:
            return False
        m = self._m
        ns = self.stamp(t if t is not None else getattr(image, "stamp", None))
        msg = m.CompressedImage(timestamp=self._ts(ns), frame_id=f"camera_{image.camera}", data=buf.tobytes(),
                                format="jpeg")
        self._log(topic, self._well_known(topic, "CompressedImage"), msg, ns)
        return True

    def scene(self, topic: str, entities: list, t: float | None = None) -> None:
        """``foxglove.SceneUpdate`` with ``entities`` (made with :mod:`.scene`)."""
        ns = self.stamp(t)
        self._log(topic, self._well_known(topic, "SceneUpdate"), self._m.SceneUpdate(entities=entities), ns)

    def close(self) -> None:
        self.closed = True
        if self.writer is not None:
            self.writer.close()
            self.writer = None
        if self.server is not None:
            self.server.stop()
            self.server = None
        for ch in self._channels.values():
            ch.close()
        self._channels.clear()

    def __enter__(self) -> Watch:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
