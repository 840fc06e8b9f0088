"""Decorator node types: retry (delay, backoff, per-attempt hook), timeout,
repeat, inverter, force_success, force_failure, one_shot and guard.

Every timing decision uses the run context's clock, never the wall clock,
so trees behave the same in a lockstep simulation.  A decorator that stops
early halts its running child (terminate with INVALID).
"""
from __future__ import annotations

from collections.abc import Callable, Iterator

import py_trees
from py_trees.common import OneShotPolicy, Status

from ..clock import Clock
from .blackboard import write_error
from .ports import Input, Output
from .registry import DEFAULT, Slot, structural

CHILD = Slot("child", doc="the decorated node")
_R, _S, _F, _I = Status.RUNNING, Status.SUCCESS, Status.FAILURE, Status.INVALID


class _Own(py_trees.decorators.Decorator):
    """A decorator that drives its own tick (it may skip ticking its child)."""

    def update(self) -> Status:
        return self.status

    def _finish(self, status: Status) -> None:
        if status is not _R:
            self.stop(status)
        self.status = status


class Retry(_Own):
    """Retry a failing child up to ``attempts`` times in total, waiting
    ``delay * backoff**(n-1)`` seconds (capped at ``max_delay``) of the
    context clock after the n-th failure.  ``on_attempt(n)`` is called as
    attempt n starts; ``on_retry`` (a behaviour) runs after each failure,
    before the wait, and its failure ends the retry.  Never retries within
    the tick that failed."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, attempts: int, clock: Clock,
                 delay: float = 0.0, backoff: float = 1.0, max_delay: float | None = None,
                 on_attempt: Callable[[int], None] | None = None,
                 on_retry: py_trees.behaviour.Behaviour | None = None):
        super().__init__(name, child)
        if attempts < 1:
            raise ValueError("attempts must be at least 1")
        self.attempts, self.clock = attempts, clock
        self.delay, self.backoff, self.max_delay = delay, backoff, max_delay
        self.on_attempt = on_attempt
        self.on_retry = on_retry
        if on_retry is not None:
            self.children.append(on_retry)
            on_retry.parent = self
        self.attempt = 0
        self._phase = "child"
        self._wait_until = 0.0

    def delay_after(self, failures: int) -> float:
        """Seconds to wait after the ``failures``-th failure."""
        d = self.delay * (self.backoff ** (failures - 1))
        return min(d, self.max_delay) if self.max_delay is not None else d

    def _start_attempt(self, n: int) -> None:
        self.attempt = n
        self._phase = "child"
        self.feedback_message = f"attempt {n}/{self.attempts}"
        if self.on_attempt is not None:
            self.on_attempt(n)

    def initialise(self) -> None:
        self._start_attempt(1)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status is not _R:
            self.initialise()
        if self._phase == "on_retry":
            yield from self.on_retry.tick()
            st = self.on_retry.status
            if st is _R:
                self.status = _R
                yield self
                return
            if st is not _S:
                self.feedback_message = f"on_retry failed after attempt {self.attempt}"
                self._finish(_F)
                yield self
                return
            self._phase = "wait"
        if self._phase == "wait":
            if self.clock.now() < self._wait_until:
                self.status = _R
                yield self
                return
            self._start_attempt(self.attempt + 1)
        yield from self.decorated.tick()
        st = self.decorated.status
        if st is _F:
            if self.attempt >= self.attempts:
                self.feedback_message = f"failed {self.attempts} attempts"
                self._finish(_F)
            else:
                self._wait_until = self.clock.now() + self.delay_after(self.attempt)
                self._phase = "on_retry" if self.on_retry is not None else "wait"
                self.status = _R
        else:
            self._finish(st)
        yield self

    def stop(self, new_status: Status) -> None:
        if self.on_retry is not None and self.on_retry.status is _R:
            self.on_retry.stop(_I)
        super().stop(new_status)


class Timeout(_Own):
    """FAILURE (halting the child) when the child has not finished within
    ``seconds`` of the context clock; optionally writes an error code."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, seconds: float, clock: Clock,
                 on_timeout: Callable[[], None] | None = None):
        super().__init__(name, child)
        self.seconds, self.clock, self.on_timeout = seconds, clock, on_timeout
        self.deadline = 0.0

    def initialise(self) -> None:
        self.deadline = self.clock.now() + self.seconds

    def _expire(self) -> None:
        if self.decorated.status is _R:
            self.decorated.stop(_I)
        self.feedback_message = f"timed out after {self.seconds:g} s"
        if self.on_timeout is not None:
            self.on_timeout()
        self._finish(_F)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status is not _R:
            self.initialise()
        elif self.clock.now() >= self.deadline:
            self._expire()
            yield self
            return
        yield from self.decorated.tick()
        st = self.decorated.status
        if st is _R and self.clock.now() >= self.deadline:
            self._expire()
        else:
            self._finish(st)
        yield self


class Guard(_Own):
    """Tick the child only while a condition holds.  ``check`` is
    ``every_tick`` (the condition is re-checked while the child runs, and a
    false condition halts it) or ``on_start`` (checked once, before the child
    starts).  When false the guard returns ``when_false``."""

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour,
                 condition: Callable[[], bool] | py_trees.behaviour.Behaviour,
                 every_tick: bool = True, when_false: Status = _F):
        super().__init__(name, child)
        self.condition_node = condition if isinstance(condition, py_trees.behaviour.Behaviour) else None
        self.condition_fn = None if self.condition_node is not None else condition
        if self.condition_node is not None:
            self.children.insert(0, self.condition_node)
            self.condition_node.parent = self
        self.every_tick, self.when_false = every_tick, when_false

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        starting = self.status is not _R
        if starting:
            self.initialise()
        if starting or self.every_tick:
            if self.condition_node is not None:
                yield from self.condition_node.tick()
                ok = self.condition_node.status is _S
            else:
                ok = bool(self.condition_fn())
            if not ok:
                if self.decorated.status is _R:
                    self.decorated.stop(_I)
                self.feedback_message = "condition is false"
                self._finish(self.when_false)
                yield self
                return
        yield from self.decorated.tick()
        self._finish(self.decorated.status)
        yield self


# -- registration -------------------------------------------------------------
def _error_hook(ctx, spec, default_message):
    code = spec.const("error_code")
    if not code:
        return None
    message = spec.const("error_message") or default_message

    def hook():
        write_error(ctx.blackboard, code, message, spec.name)
    return hook


def _build_retry(spec, slots, ctx):
    key = spec.ports.get("attempt")
    hook = None
    if key is not None:
        def hook(n, _bb=ctx.blackboard, _k=key.key):
            _bb.set(_k, n)
    on_retry = slots.get("on_retry", [None])[0] if slots.get("on_retry") else None
    return Retry(spec.name, slots["child"][0], spec.const("attempts"), ctx.clock, spec.const("delay"),
                 spec.const("backoff"), spec.const("max_delay"), hook, on_retry)


def _at_least(port: str, low: float, strict: bool = False, allow: tuple = ()):
    def check(spec, opts):
        v = spec.const(port)
        if v is None or v in allow:
            return []
        if v < low or (strict and v == low):
            word = "greater than" if strict else "at least"
            extra = f" (or {', '.join(map(str, allow))})" if allow else ""
            return [(opts.vloc(port), f"`{port}` must be {word} {low:g}{extra}, got {v!r}",
                     f"set {port} to {word} {low:g}")]
        return []
    return check


def _checks(*fns):
    def check(spec, opts):
        out = []
        for f in fns:
            out.extend(f(spec, opts))
        return out
    return check


DEFAULT.register(structural(
    "retry", "decorator", """
    Run the child again when it fails, up to ``attempts`` tries in all, with a
    pause of ``delay`` seconds (context clock) after the first failure that
    grows by ``backoff`` after each further failure, capped at
    ``max_delay``.  ``attempt`` receives the number of the attempt being
    made (1, 2, ...), and ``on_retry`` (a node) runs after each failed try,
    before the pause; if it fails, the retry fails.  A retry never starts
    again in the tick that failed.""",
    (Input(int, "tries in all (at least 1)", constant=True, name="attempts"),
     Input(float, "seconds to wait after the first failure", default=0.0, constant=True, name="delay"),
     Input(float, "factor by which the wait grows after each failure", default=1.0, constant=True,
           name="backoff"),
     Input(float, "longest wait in seconds", required=False, constant=True, name="max_delay"),
     Output(int, "the number of the attempt being made", name="attempt")),
    (CHILD, Slot("on_retry", required=False, doc="a node run after each failed attempt")),
    _build_retry,
    _checks(_at_least("attempts", 1), _at_least("delay", 0.0), _at_least("backoff", 1.0),
            _at_least("max_delay", 0.0))))

DEFAULT.register(structural(
    "timeout", "decorator", """
    Fail, halting the child, when it has not finished within ``seconds`` of
    the context clock.  With ``error_code``, a timeout also writes the error
    code (and ``error_message``) for the agent to report.""",
    (Input(float, "seconds the child may take", constant=True, name="seconds"),
     Input(str, "error code written when the time is up", required=False, constant=True, name="error_code"),
     Input(str, "error message written with the code", required=False, name="error_message", constant=True)),
    (CHILD,),
    lambda spec, slots, ctx: Timeout(spec.name, slots["child"][0], spec.const("seconds"), ctx.clock,
                                     _error_hook(ctx, spec, f"{spec.name} timed out after "
                                                 f"{spec.const('seconds'):g} s")),
    _at_least("seconds", 0.0, strict=True)))

DEFAULT.register(structural(
    "repeat", "decorator", """
    Run the child ``count`` times, one run per tick at most; SUCCESS after the
    last success, FAILURE at the first failure.  ``count: -1`` repeats
    forever.""",
    (Input(int, "how many successful runs (-1: forever)", constant=True, name="count"),),
    (CHILD,),
    lambda spec, slots, ctx: py_trees.decorators.Repeat(spec.name, slots["child"][0], spec.const("count")),
    _at_least("count", 1, allow=(-1,))))

DEFAULT.register(structural(
    "inverter", "decorator", "SUCCESS becomes FAILURE and FAILURE becomes SUCCESS; RUNNING passes.", (),
    (CHILD,), lambda spec, slots, ctx: py_trees.decorators.Inverter(spec.name, slots["child"][0])))

DEFAULT.register(structural(
    "force_success", "decorator", "FAILURE becomes SUCCESS; RUNNING and SUCCESS pass.", (), (CHILD,),
    lambda spec, slots, ctx: py_trees.decorators.FailureIsSuccess(spec.name, slots["child"][0])))

DEFAULT.register(structural(
    "force_failure", "decorator", "SUCCESS becomes FAILURE; RUNNING and FAILURE pass.", (), (CHILD,),
    lambda spec, slots, ctx: py_trees.decorators.SuccessIsFailure(spec.name, slots["child"][0])))

_ONE_SHOT = {"on_success": OneShotPolicy.ON_SUCCESSFUL_COMPLETION, "on_completion": OneShotPolicy.ON_COMPLETION}
DEFAULT.register(structural(
    "one_shot", "decorator", """
    Run the child to completion once; afterwards return that result without
    ticking it again.  ``policy: on_success`` (default) lets a failed child
    run again next time; ``on_completion`` keeps the first result, success or
    failure.""",
    (Input(str, "when the shot counts as done", default="on_success", choices=tuple(_ONE_SHOT),
           constant=True, name="policy"),),
    (CHILD,),
    lambda spec, slots, ctx: py_trees.decorators.OneShot(spec.name, slots["child"][0],
                                                         _ONE_SHOT[spec.const("policy")])))


def _build_guard(spec, slots, ctx):
    expr = spec.const("condition")
    cond = expr.bind(ctx.blackboard) if expr is not None else slots["condition"][0]
    when = _S if spec.const("when_false") == "success" else _F
    return Guard(spec.name, slots["child"][0], cond, spec.const("check") == "every_tick", when)


DEFAULT.register(structural(
    "guard", "decorator", """
    Run the child only while ``condition`` holds.  The condition is a
    condition expression (``"holding == true and attempts < 3"``) or a
    condition node.  ``check: every_tick`` (default) re-checks it while the
    child runs and halts the child when it turns false; ``on_start`` checks
    it once before the child starts.  When false the guard returns
    ``when_false`` (failure by default, or success to skip the child).""",
    (Input(str, "when the condition is checked", default="every_tick", choices=("every_tick", "on_start"),
           constant=True, name="check"),
     Input(str, "the guard's result when the condition is false", default="failure",
           choices=("failure", "success"), constant=True, name="when_false")),
    (Slot("condition", expr=True, doc="a condition expression or a condition node"), CHILD),
    _build_guard))
