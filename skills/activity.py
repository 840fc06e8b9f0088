"""Non-blocking activities: ``start`` / ``poll`` / ``cancel`` on a clock.

Every skill is an :class:`Activity`.  ``poll()`` does a bounded amount of
work (one control step), sends at most one command to the backend and
returns the status; nothing ever waits.  A behaviour-tree node wraps one
activity: ``initialise`` starts it, ``update`` polls it, ``terminate``
cancels it (which stops the robot).

Subclasses implement :meth:`_on_start`, :meth:`_step` and optionally
:meth:`_on_stop`; a step returns ``Status.RUNNING`` or ``Status.SUCCESS``,
or raises :class:`~skills.errors.SkillFailure` to fail with a code.
"""
from __future__ import annotations

import enum
import logging

from rll_bt.backend import BackendError, SensorLost

from .errors import SkillError, SkillFailure

log = logging.getLogger(__name__)


class Status(enum.Enum):
    IDLE = "idle"
    RUNNING = "running"
    SUCCESS = "success"
    FAILURE = "failure"
    CANCELLED = "cancelled"

    @property
    def done(self) -> bool:
        return self in (Status.SUCCESS, Status.FAILURE, Status.CANCELLED)


class Activity:
    """Base class.  ``ctx`` is a :class:`skills.context.SkillContext`;
    ``timeout`` is in seconds of ``ctx.clock`` (None: no limit)."""

    name = "activity"

    def __init__(self, ctx, timeout: float | None = None):
        self.ctx = ctx
        self.timeout = timeout
        self.status = Status.IDLE
        self.error = SkillError.NONE
        self.message = ""
        self.started_at: float | None = None
        self.finished_at: float | None = None

    # -- public API -------------------------------------------------------
    def start(self) -> Activity:
        """Begin (or restart) the activity.  Returns self."""
        self.status = Status.RUNNING
        self.error = SkillError.NONE
        self.message = ""
        self.started_at = self.ctx.clock.now()
        self.finished_at = None
        try:
            self._on_start()
        except SkillFailure as exc:
            self._finish(Status.FAILURE, exc.code, exc.message)
        except SensorLost as exc:
            self._finish(Status.FAILURE, SkillError.SENSOR_LOST, f"{self.name}: {exc}")
        return self

    def poll(self) -> Status:
        """One control step; returns the status.  Idempotent once done."""
        if self.status is not Status.RUNNING:
            return self.status
        now = self.ctx.clock.now()
        try:
            self.ctx.update()
            if self.timeout is not None and now - self.started_at > self.timeout:
                raise SkillFailure(SkillError.TIMEOUT,
                                   f"{self.name} did not finish within {self.timeout:.1f} s")
            result = self._step(now)
        except SkillFailure as exc:
            self._finish(Status.FAILURE, exc.code, exc.message)
        except SensorLost as exc:          # the backend stopped the robot itself
            self._finish(Status.FAILURE, SkillError.SENSOR_LOST, f"{self.name}: {exc}")
        except BackendError as exc:
            self._finish(Status.FAILURE, SkillError.INTERNAL, f"{self.name}: {exc}")
        else:
            if result is Status.SUCCESS:
                self._finish(Status.SUCCESS, SkillError.NONE, self.message)
        return self.status

    def cancel(self) -> None:
        """Stop at once (the robot stops); no-op when already done."""
        if self.status is Status.RUNNING:
            self._finish(Status.CANCELLED, SkillError.CANCELLED, f"{self.name} cancelled")

    @property
    def elapsed(self) -> float:
        if self.started_at is None:
            return 0.0
        end = self.finished_at if self.finished_at is not None else self.ctx.clock.now()
        return end - self.started_at

    def run(self, step: float = 0.1, advance=None, limit: float = 600.0) -> Status:
        """Poll until done (tests, scripts).  ``advance(step)`` moves the
        world and clock forward between polls; without it the clock's own
        ``sleep`` is used."""
        if self.status is Status.IDLE:
            self.start()
        t_end = self.ctx.clock.now() + limit
        while self.poll() is Status.RUNNING:
            if self.ctx.clock.now() > t_end:
                self.cancel()
                break
            if advance is not None:
                advance(step)
            else:
                self.ctx.clock.sleep(step)
        return self.status

    # -- for subclasses ---------------------------------------------------
    def _on_start(self) -> None:
        pass

    def _step(self, now: float) -> Status:
        raise NotImplementedError

    def _on_stop(self, status: Status) -> None:
        """Called once when the activity ends; by default stops the base."""
        self.ctx.stop_base()

    def _finish(self, status: Status, code: SkillError, message: str) -> None:
        self.status = status
        self.error = code
        self.message = message
        self.finished_at = self.ctx.clock.now()
        try:
            self._on_stop(status)
        except BackendError as exc:    # stopping must not turn into a crash
            log.warning("%s: stopping failed: %s", self.name, exc)
        if status is Status.FAILURE:
            log.info("%s failed: %s %s", self.name, code.value, message)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.status.value} {self.error.value} {self.message!r}>"


class Sequence(Activity):
    """Run child activities one after the other; fails with the first
    failing child's code.  Children are created lazily by factories so each
    sees the state the previous one left; a factory may return None to skip
    its step."""

    name = "sequence"

    def __init__(self, ctx, factories, timeout: float | None = None, name: str | None = None):
        super().__init__(ctx, timeout)
        self._factories = list(factories)
        self._index = 0
        self.current: Activity | None = None
        if name:
            self.name = name

    def _on_start(self) -> None:
        self._index = 0
        self.current = None

    def _step(self, now: float) -> Status:
        while True:
            if self.current is None:
                if self._index >= len(self._factories):
                    self.message = f"{self.name}: done"
                    return Status.SUCCESS
                child = self._factories[self._index]()
                self._index += 1
                if child is None:
                    continue
                self.current = child.start()
            status = self.current.poll()
            if status is Status.RUNNING:
                return Status.RUNNING
            if status is not Status.SUCCESS:
                raise SkillFailure(self.current.error, self.current.message)
            self.current = None
            # the next child starts in the same tick, so a sequence of quick
            # steps does not waste ticks, but each child gets only one poll

    def _on_stop(self, status: Status) -> None:
        if self.current is not None and self.current.status is Status.RUNNING:
            self.current.cancel()
        else:
            self.ctx.stop_base()
