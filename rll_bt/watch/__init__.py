"""Watching robots and games with Foxglove: MCAP recordings and a live
WebSocket server through the ``foxglove-sdk`` (:mod:`.sink`), and what one
robot puts on them (:mod:`.robot`).  Install with ``pip install 'rll-bt[watch]'``."""
from .robot import RobotWatch, TappedBackend
from .sink import Watch, WatchUnavailable

__all__ = ["RobotWatch", "TappedBackend", "Watch", "WatchUnavailable"]
