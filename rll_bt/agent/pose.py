"""The robot's field pose for beacons and status messages.

Sources, best first:

1. ``services["pose"]``: an object with ``pose() -> Pose2D | None`` and
   optionally ``confidence`` (0..1), or a callable returning a Pose2D;
2. any service with a ``pose_source`` of that shape (the skills' context,
   whose localiser is the robot's best estimate);
3. the backend's odometry composed onto ``start`` (the start pose in the
   field frame), with confidence ``odometry_confidence``.

Field frame of the rules profile, metres and radians.
"""
from __future__ import annotations

import logging
from typing import Any

from ..backend import Backend, BackendError, Pose2D

log = logging.getLogger("rll_bt.agent")


def _ask(source: Any) -> tuple[Pose2D | None, float] | None:
    try:
        if hasattr(source, "pose") and callable(source.pose):
            p = source.pose()
        elif callable(source):
            p = source()
        else:
            return None
    except Exception:       # no pose yet (a localiser not initialised)
        return None, 0.0
    conf = getattr(source, "confidence", 1.0)
    try:
        conf = float(conf() if callable(conf) else conf)
    except (TypeError, ValueError):
        conf = 0.0
    return p, conf


class PoseReader:
    def __init__(self, backend: Backend | None, services: dict[str, Any], start: Pose2D | None = None,
                 odometry_confidence: float = 0.3):
        self.backend = backend
        self.services = services
        self.start = start
        self.odometry_confidence = odometry_confidence
        self._odom0: Pose2D | None = None
        self._warned = False

    def read(self) -> tuple[Pose2D | None, float]:
        """(pose, confidence); (None, 0) when nothing knows the pose."""
        svc = self.services.get("pose")
        if svc is not None:
            got = _ask(svc)
            if got is not None:
                return got
        for s in self.services.values():
            src = getattr(s, "pose_source", None)
            if src is not None:
                got = _ask(src)
                if got is not None and got[0] is not None:
                    return got
        return self._odometry()

    def _odometry(self) -> tuple[Pose2D | None, float]:
        if self.backend is None:
            return None, 0.0
        try:
            odom = self.backend.odometry().pose
        except BackendError as exc:
            if not self._warned:
                log.warning("no pose for beacons: odometry failed: %s", exc)
                self._warned = True
            return None, 0.0
        if self.start is None:
            return odom, self.odometry_confidence
        if self._odom0 is None:
            self._odom0 = odom
        return self.start.compose(odom.relative_to(self._odom0)), self.odometry_confidence
