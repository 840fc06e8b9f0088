"""A simulated robot in a PyBullet world of its own, for the command line.

``rll-bt tree run FILE --backend sim`` and ``rll-bt agent --backend sim``
have nobody who owns a world and steps it, so :func:`backends.sim.open_sim`
without ``world=`` builds one (``profile``, ``seed``, ``perception``, headless
unless ``gui``) and returns a :class:`StandaloneSimBackend`: before every call
it advances the world to the caller's clock (real time on the wall clock; with
a simulated clock, to wherever that clock was moved).  Closing the backend
closes the world.
"""
from __future__ import annotations

import functools

from rll_bt.clock import Clock

from .backend import SimBackend
from .world import World

#: the most a single call catches up, in world seconds (a paused process must
#: not make the next call simulate minutes at once)
MAX_CATCH_UP = 2.0

_SYNCED = ("drive", "stop", "odometry", "laser_scan", "camera_image", "detections", "bumper", "battery",
           "gripper_open", "gripper_close", "gripper_move", "gripper_status")


def _synced(name: str):
    base = getattr(SimBackend, name)

    @functools.wraps(base)
    def method(self, *args, **kwargs):
        self.sync()
        return base(self, *args, **kwargs)
    return method


class StandaloneSimBackend(SimBackend):
    """A :class:`SimBackend` that owns its world and keeps it at ``clock``'s time."""

    name = "sim"

    def __init__(self, world: World, clock: Clock, robot=1, **options):
        super().__init__(world, robot, **options)
        self.clock = clock
        self._offset = world.time - clock.now()

    def sync(self) -> float:
        """Step the world up to the clock's time (at most :data:`MAX_CATCH_UP` s
        at once; time beyond that is skipped).  Returns the world time."""
        w = self.world
        target = self.clock.now() + self._offset
        behind = target - w.time
        if behind > MAX_CATCH_UP:
            self._offset -= behind - MAX_CATCH_UP
            behind = MAX_CATCH_UP
        if behind > 1e-9 and w.connected:
            w.step(behind)
        return w.time

    def close(self) -> None:
        try:
            super().close()
        finally:
            if self.world.connected:
                self.world.close()


for _name in _SYNCED:
    setattr(StandaloneSimBackend, _name, _synced(_name))
del _name
