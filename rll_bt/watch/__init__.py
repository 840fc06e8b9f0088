"""Watching robots and games with Foxglove: MCAP recordings and a live
WebSocket server through the ``foxglove-sdk`` (:mod:`.sink`), what one
robot puts on them (:mod:`.robot`), the messages a process sends and
receives (:mod:`.links`) and one process of a team on the wall clock
(:mod:`.process`).  Install with ``pip install 'rll-bt[watch]'``."""
from .links import LinkRecorder, WatchedTransport
from .process import wall_watch, watch_agent, watch_links
from .robot import RobotWatch, TappedBackend
from .sink import Watch, WatchUnavailable

__all__ = ["LinkRecorder", "RobotWatch", "TappedBackend", "Watch", "WatchUnavailable", "WatchedTransport",
           "wall_watch", "watch_agent", "watch_links"]
