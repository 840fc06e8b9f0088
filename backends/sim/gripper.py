"""The simulated gripper's mechanics: three linear axes and the fingers.

Axes (metres): ``x`` pushes the gripper forward beyond the robot's reach
(0 .. 0.15), ``y`` moves it sideways (-0.1 .. 0.1), ``z`` is its height above
the floor (0 .. 1.0).  The gripper point in the robot frame is
``(ROBOT.gripper_reach + x, y, z)``.  Commands queue: each runs after the one
before it, a move at ``speed`` per axis, opening or closing in ``finger_time``
seconds; :meth:`Gripper.update` reports the finger actions that finished so
the world can pick up or put down a workpiece at that moment.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from rll_bt.backend import BackendError, GripperState

X_RANGE = (0.0, 0.15)
Y_RANGE = (-0.10, 0.10)
Z_RANGE = (0.0, 1.0)


@dataclass
class _Action:
    kind: str                        # "open", "close", "move"
    target: tuple[float, float, float] | None = None
    start: float = 0.0
    end: float = 0.0
    origin: tuple[float, float, float] | None = None


class Gripper:
    def __init__(self, home: tuple[float, float, float], speed: float, finger_time: float):
        self.position = tuple(float(v) for v in home)
        self.is_open = True
        self.speed = speed
        self.finger_time = finger_time
        self._queue: deque[_Action] = deque()
        self._current: _Action | None = None

    def command(self, kind: str, target=None, now: float = 0.0) -> None:
        """Queue an action; it starts at ``now`` when the gripper is idle."""
        if kind == "move":
            x, y, z = (float(v) for v in target)
            for name, v, (lo, hi) in (("x", x, X_RANGE), ("y", y, Y_RANGE), ("z", z, Z_RANGE)):
                if not lo <= v <= hi:
                    raise BackendError(f"gripper {name}={v:.3f} m is outside {lo}..{hi} m")
            target = (x, y, z)
        self._queue.append(_Action(kind, target))
        if self._current is None:
            self._start_next(now)

    def _start_next(self, t: float) -> None:
        a = self._queue.popleft()
        a.start, a.origin = t, self.position
        if a.kind == "move":
            a.end = t + max(abs(g - o) for g, o in zip(a.target, a.origin)) / self.speed
        else:
            a.end = t + self.finger_time
        self._current = a

    @property
    def busy(self) -> bool:
        return self._current is not None or bool(self._queue)

    def update(self, now: float) -> list[str]:
        """Advance to ``now``; return the finger actions ("open"/"close") that finished."""
        done: list[str] = []
        while self._current is not None:
            a = self._current
            if now < a.end:
                if a.kind == "move":
                    f = (now - a.start) / (a.end - a.start)
                    self.position = tuple(o + f * (g - o) for o, g in zip(a.origin, a.target))
                break
            if a.kind == "move":
                self.position = a.target
            else:
                self.is_open = a.kind == "open"
                done.append(a.kind)
            self._current = None
            if self._queue:
                self._start_next(a.end)
        return done

    def state(self) -> GripperState:
        return GripperState.MOVING if self.busy else GripperState.IDLE
