"""What every station shares: states, lights, timed steps, breaking, down periods.

States and their lights: :mod:`.lights`.

A station works in timed *steps*, each as long as the real machine takes
(:class:`rll_bt.rules.MachineTimes`): waiting for the workpiece on the input,
the belt to the middle, the operation, the belt to the output.  The 2016
refbox calls the machine PROCESSING from the moment the workpiece is on its
input; today's keeps it PREPARED until the belt has brought it to the middle.

Breaking (each with the refbox's reason, kept in ``broken_reason`` and, as a
short key, ``broken_cause``; an attention message goes out): a wrong or
missing instruction (an RS colour the RS lacks, RETRIEVE_CAP while a cap is
buffered, MOUNT_CAP without one), an RS started without its additional
bases, a workpiece the operation cannot work on, more than 3 bases on a
slide, a ResetMachine; 2016: a workpiece put on the input of a machine that
is not PREPARED for it (the workpiece is lost); 2025: a machine PREPARED,
PROCESSING or PROCESSED for ``stuck_timeout`` (20 s) without progress, and
every break takes back the points of unused slide bases and of a retrieved
cap.  A DOWN period freezes the station's timers and restores its state.
A prepared machine left without its workpiece (timed out, broken, reset, or
still waiting at the end) is a ``referee`` event: the rulebook's penalty for
instructing a machine without placing a workpiece.  Times are game seconds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from rll_bt.rules import BROKEN_TIME, MPS_TIMES, PREPARED_BLINK_TIME, WAIT_IDLE_TIME, MachineTimes

from .. import events as E
from ..world import ALL_OFF, INPUT, OUTPUT, Workpiece, describe, station_slots
from .lights import (  # noqa: F401 (the states are this module's names too)
    BROKEN,
    DOWN,
    IDLE,
    PREPARED,
    PREPARED_BLINK,
    PROCESSED,
    PROCESSING,
    READY_AT_OUTPUT,
    STATE_LIGHTS,
    STATES,
    WAIT_IDLE,
    light_text,
)

#: states the 2025 refbox breaks a machine in after ``stuck_timeout`` without progress
BUSY_STATES = (PREPARED, PROCESSING, PROCESSED)

# steps (what the machine is doing inside its state)
INPUT_STEP, MIDDLE, OPERATION, TO_OUTPUT = "input", "middle", "operation", "output"
WAIT_STEP, OUT_STEP, WINDOW = "wait", "out", "window"


@dataclass(frozen=True)
class StationConfig:
    """Machine times and the refbox's station timings, game seconds.

    ``times`` are the real machines' (:data:`rll_bt.rules.MPS_TIMES`); the rest
    are the refbox's globals.clp.  ``delivery_confirm`` is how long the
    simulated referee takes to confirm a 2025 delivery (0: at once).
    """

    times: MachineTimes = MPS_TIMES
    prepared_blink: float = PREPARED_BLINK_TIME
    wait_idle: float = WAIT_IDLE_TIME
    broken: float = BROKEN_TIME
    slide_max: int = 3                     # LOADED-WITH-MAX
    cs_caps: tuple[tuple[str, str], ...] = (("CS1", "CAP_GREY"), ("CS2", "CAP_BLACK"))
    carrier_base: str = "BASE_RED"         # base under the caps on a CS shelf
    delivery_confirm: float = 0.0

    def cap_of(self, kind: str) -> str:
        return dict(self.cs_caps)[kind]


class StationHost(Protocol):
    """What a station needs from the game."""

    world: object
    config: StationConfig
    profile: object
    rules: object

    def station_lights(self, station: Station) -> dict: ...
    def ring_cost(self, color: str) -> int: ...
    def rs_colors(self, machine: str) -> tuple[str, ...]: ...
    def order(self, order_id: int): ...
    def award(self, team: str, points: int, reason: str, machine: str | None = None,
              game_time: float | None = None) -> None: ...
    def emit(self, kind: str, text: str, *, team: str | None = None, machine: str | None = None,
             game_time: float | None = None, **data) -> None: ...
    def referee(self, what: str, text: str, *, team: str | None, machine: str | None = None,
                game_time: float | None = None, **data) -> None: ...
    def deliver(self, station: Station, wp: Workpiece, gate: int, game_time: float) -> None: ...
    def station_state_changed(self, station: Station, previous: str) -> None: ...
    def rng(self, stream: str): ...


@dataclass
class Station:
    """One station's production state.  ``now`` is the station's game time
    (production seconds) as of its last :meth:`update`; ``step`` what it is
    doing, ``deadline`` when that step ends (None: it waits for something),
    ``proc_start`` when its current PREPARED/PROCESSING/PROCESSED began."""

    name: str
    team: str
    host: StationHost
    state: str = IDLE
    prev_state: str | None = None
    lights: dict = field(default_factory=lambda: dict(ALL_OFF))
    now: float = 0.0
    active: bool = False
    step: str | None = None
    deadline: float | None = None
    proc_start: float | None = None
    blink_until: float | None = None
    down: tuple[float, float] | None = None
    down_done: bool = False
    broken_reason: str = ""
    broken_cause: str = ""
    instruction: object = None
    input_wp: Workpiece | None = None
    input_while_down: bool = False
    fed: bool = False
    inside: Workpiece | None = None
    out_slot: str = OUTPUT
    bases_added: int = 0
    bases_used: int = 0
    cap_buffer: str | None = None

    kind = "?"

    # -- phase ----------------------------------------------------------------
    def start_production(self, game_time: float) -> None:
        """Enter production: IDLE with its lights."""
        self.active, self.now = True, game_time
        self._set_state(IDLE, "production started")

    def stop_production(self) -> None:
        """PRODUCTION is over: a machine still waiting for its workpiece is reported."""
        if self.active and self._waits_for_workpiece():
            self._unfed("still waiting for its workpiece at the end of production")
        self.active = False

    # -- inputs ------------------------------------------------------------------
    def prepare(self, instr) -> None:
        """A PrepareMachine for this (IDLE) station; the game checked phase, team and state."""
        reason = self.validate(instr)
        if reason:
            sep = "" if reason[:1] in (":", ",") else " "
            self.break_(f"Prepare received for {self.name}{sep}{reason}", "prepare")
            return
        self.instruction, self.fed = instr, False
        self.blink_until = self.now + self.host.config.prepared_blink
        self.step, self.deadline = (INPUT_STEP if self.wants_input() else None), None
        self._set_state(PREPARED, f"prepared: {instr}")
        self.on_prepared()
        self._maybe_start()

    def on_put(self, slot: str, wp, robot=None) -> None:
        """A robot (``robot``: (team, number) or None) put ``wp`` on ``slot``."""
        if slot != INPUT:
            return
        self.input_wp = describe(wp)
        if self.state == DOWN:
            self.input_while_down = True
            return
        if not self._input_check():
            self._maybe_start()

    def feed(self, wp: Workpiece) -> None:
        """A workpiece fed to the input without a world (mockup mode): processed at once
        when the station waits for it, else kept until it does."""
        self.input_wp = wp
        self._maybe_start()

    def on_take(self, slot: str, wp: Workpiece | None) -> None:
        if slot == INPUT:
            self.input_wp = None
        if slot != self.out_slot or self.inside is not None:
            return
        if self.state == READY_AT_OUTPUT:
            self._wait_idle("product taken")
        elif self.state == DOWN and self.prev_state == READY_AT_OUTPUT:
            self.prev_state = IDLE      # taken while down: idle once up again

    def update(self, game_time: float) -> None:
        """Run every timed transition due up to ``game_time``, each at its own time."""
        if not self.active:
            self.now = max(self.now, game_time)
            return
        self._maybe_start()
        while True:
            t, what = self._next_timer()
            if t is None or t > game_time:
                break
            self.now = max(self.now, t)
            what()
            self._maybe_start()
        self.now = max(self.now, game_time)

    # -- kind hooks ------------------------------------------------------------
    def validate(self, instr) -> str | None:
        """Why ``instr`` breaks this station at the prepare, as the refbox's text after
        "Prepare received for NAME" (e.g. "without data"); None when it is fine."""
        return None

    def wants_input(self) -> bool:
        """Whether the prepared operation waits for a workpiece on the input."""
        return True

    def on_prepared(self) -> None:
        """Right after the prepare (the machine is PREPARED)."""

    def start(self, wp: Workpiece) -> tuple[str, str] | None:
        """The workpiece ``wp`` taken off the input: (reason, cause) to break instead, or
        None to work on it."""
        return None

    def operation_time(self) -> float:
        """Seconds of the operation (under the tool)."""
        return self.host.config.times.minimum

    def finish(self) -> None:
        """The operation is done (the station is PROCESSING)."""
        raise NotImplementedError

    @property
    def times(self) -> MachineTimes:
        return self.host.config.times

    def _emit(self, kind: str, text: str, **data) -> None:
        """An event at this station's own game time (its transitions are exact)."""
        self.host.emit(kind, text, game_time=self.now, **data)

    def _award(self, team: str, points: int, reason: str, **data) -> None:
        self.host.award(team, points, reason, game_time=self.now, **data)

    # -- steps -------------------------------------------------------------------
    def _maybe_start(self) -> None:
        """Take the workpiece off the input when the station waits for one."""
        if not (self.active and self.step == INPUT_STEP and self.input_wp is not None
                and self.state in (PREPARED, PROCESSING)):
            return
        taken = self.host.world.remove_workpiece(self.name, INPUT)
        wp = describe(taken) if taken is not None else self.input_wp
        self.input_wp, self.fed = None, True
        why = self.start(wp)
        if why:
            self.break_(*why)
            return
        self.inside = wp
        self.on_input(wp)

    def on_input(self, wp: Workpiece) -> None:
        """The workpiece is in: the belt carries it to the middle.  The 2016 refbox calls
        that PROCESSING already (its PLC reports the input), today's keeps PREPARED."""
        if self.host.rules.processing_from_input and self.state != PROCESSING:
            self._set_state(PROCESSING, "workpiece on the input")
        self._step(MIDDLE, self.times.belt_to_middle)

    def _operate(self) -> None:
        if self.state != PROCESSING:
            self._set_state(PROCESSING, f"processing {self.instruction}")
        self.proc_start = self.now           # the operation starts: progress
        self._step(OPERATION, max(self.operation_time(), self.times.minimum))

    def _processed(self, wp: Workpiece | None, slot: str = OUTPUT,
                   move: float | None = None) -> None:
        """The operation is done: PROCESSED while the belt carries ``wp`` to ``slot``."""
        self.inside, self.out_slot = wp, slot
        self._set_state(PROCESSED, f"{wp} to the {slot}")
        self._step(TO_OUTPUT, self.times.belt_to_output if move is None else move)

    def _ready(self) -> None:
        wp, slot = self.inside, self.out_slot
        if self.host.world.workpiece_at(self.name, slot) is not None:
            self.break_(f"{self.name}: cannot put {wp} on the {slot}, it is occupied", "occupied")
            return
        self.host.world.spawn_workpiece(self.name, slot, wp.base, tuple(wp.rings), wp.cap)
        self._emit(E.WORKPIECE, f"{self.name} put {wp} on {slot}", team=self.team,
                       machine=self.name, workpiece=wp, slot=slot)
        self.inside, self.step, self.deadline = None, None, None
        self._set_state(READY_AT_OUTPUT, f"{wp} ready at {slot}")

    def _wait_idle(self, why: str) -> None:
        self.instruction, self.inside = None, None
        wait = self.host.config.wait_idle
        if wait > 0:
            self._set_state(WAIT_IDLE, why)
            self._step(WAIT_STEP, wait)
        else:
            self._idle(why)

    def _idle(self, why: str) -> None:
        self.instruction, self.step, self.deadline = None, None, None
        self._set_state(IDLE, why)

    def _step(self, step: str, seconds: float) -> None:
        self.step, self.deadline = step, self.now + seconds

    def _step_done(self) -> None:
        step, self.deadline = self.step, None
        if step == MIDDLE:
            self._operate()
        elif step == OPERATION:
            self.finish()
        elif step == TO_OUTPUT:
            self._ready()
        elif step == WAIT_STEP:
            self._idle("ready again")
        elif step == OUT_STEP:
            self._recover()
        else:
            self.on_timer(step)

    def on_timer(self, step: str | None) -> None:
        """A step of the kind's own has reached its deadline."""

    # -- breaking -------------------------------------------------------------------
    def break_(self, reason: str, cause: str = "other") -> None:
        """BROKEN for ``config.broken`` s with the refbox's ``reason``; ``cause`` is a short
        key for counting ("prepare", "not-prepared", "timeout", "reset", ...)."""
        if self._waits_for_workpiece():
            self._unfed(f"broken while waiting for its workpiece ({cause})")
        self.broken_reason, self.broken_cause = reason, cause
        self.instruction, self.inside = None, None
        self._clear_slots()
        self._set_state(BROKEN, self.broken_reason, cause=cause)
        self._step(OUT_STEP, self.host.config.broken)
        self._emit(E.ATTENTION, self.broken_reason, team=self.team, machine=self.name,
                       time_to_show=10.0)
        if self.host.profile.scoring.break_revokes:
            self.revoke_points()

    def revoke_points(self) -> None:
        """2025: what a break takes back (RS slide bases, a CS's retrieved cap)."""

    def _input_check(self) -> bool:
        """2016: a workpiece on the input of a machine not PREPARED breaks it (the
        workpiece is lost).  True when it broke the machine."""
        if not self.host.profile.unprepared_input_breaks or self.input_wp is None:
            return False
        if self.state in (PREPARED, BROKEN, DOWN, PROCESSING):
            return False
        self.host.world.remove_workpiece(self.name, INPUT)
        self.input_wp = None
        self.break_(f"Input to {self.name} while not prepared {self.state}", "not-prepared")
        return True

    def awaits_workpiece(self) -> bool:
        """Prepared and waiting for its workpiece on the input (a 2025 DS also while its
        order's window has not opened)."""
        return (self.state in (PREPARED, PROCESSING) and self.step in (INPUT_STEP, WINDOW)
                and self.wants_input())

    def _waits_for_workpiece(self) -> bool:
        """Prepared for a workpiece that never came (and none lies on the input)."""
        return self.awaits_workpiece() and not self.fed and self.input_wp is None

    def _unfed(self, text: str) -> None:
        self.fed = True                  # reported once
        self.host.referee("prepare-without-workpiece", f"{self.name} prepared, {text}",
                          team=self.team, machine=self.name, game_time=self.now)

    def _stuck(self) -> None:
        self.break_(f"{self.name}: stuck in state {self.state} for > "
                    f"{self.host.profile.stuck_timeout:.0f}s", "timeout")

    def _recover(self) -> None:
        self.bases_used = self.bases_added
        self.cap_buffer = None
        self._clear_slots()
        self.broken_reason, self.broken_cause = "", ""
        self._idle("recovered")

    # -- timers ----------------------------------------------------------------------
    def _next_timer(self):
        cand = []
        if self.state == DOWN:
            cand.append((self.down[1], self._down_end))
        else:
            if self.down is not None and not self.down_done:
                cand.append((self.down[0], self._down_start))
            if self.blink_until is not None:
                cand.append((self.blink_until, self._blink_end))
            if self.deadline is not None:
                cand.append((self.deadline, self._step_done))
            limit = self.host.profile.stuck_timeout
            if limit is not None and self.state in BUSY_STATES and self.proc_start is not None:
                cand.append((self.proc_start + limit, self._stuck))
        if not cand:
            return None, None
        return min(cand, key=lambda c: c[0])

    def _blink_end(self) -> None:
        self.blink_until = None
        self._show_lights()

    def _down_start(self) -> None:
        start, end = self.down
        self.down_done = True
        length = end - start
        if self.deadline is not None:
            self.deadline += length
        if self.blink_until is not None:
            self.blink_until += length
        if self.proc_start is not None:
            self.proc_start += length
        self.prev_state = self.state
        self._set_state(DOWN, f"down for {length:.0f} s")

    def _down_end(self) -> None:
        back = self.prev_state or IDLE
        self.prev_state = None
        self._set_state(back, "up again", keep_proc_start=True)
        if self.input_while_down:
            self.input_while_down = False
            self._input_check()

    def _clear_slots(self) -> None:
        for slot in (INPUT, OUTPUT):
            if slot in station_slots(self.name) and \
                    self.host.world.workpiece_at(self.name, slot) is not None:
                self.host.world.remove_workpiece(self.name, slot)
        self.input_wp = None

    def _set_state(self, state: str, why: str, *, keep_proc_start: bool = False,
                   **data) -> None:
        prev, self.state = self.state, state
        if state != PREPARED:
            self.blink_until = None
        if state in BUSY_STATES:
            if not keep_proc_start:
                self.proc_start = self.now
        elif state != DOWN:
            self.proc_start = None
        self._show_lights()
        self._emit(E.MACHINE, f"{self.name} {prev} -> {state}: {why}", team=self.team,
                       machine=self.name, state=state, previous=prev, reason=why, **data)
        self.host.station_state_changed(self, prev)

    # -- lights ----------------------------------------------------------------------
    def _show_lights(self) -> None:
        self.set_lights(self.host.station_lights(self))

    def state_lights(self, table: dict | None = None) -> dict:
        """The tower for the current state from ``table`` (state -> lights); by default
        2016's, which blinks green only for the first seconds of PREPARED."""
        if table is None:
            if self.state == PREPARED and self.blink_until is not None:
                return PREPARED_BLINK
            table = STATE_LIGHTS
        return table[self.state]

    def reset(self, reason: str) -> None:
        """A team's ResetMachine: BROKEN now (or, while DOWN, once the down period ends)."""
        if self.state == DOWN:
            self.broken_reason, self.broken_cause = reason, "reset"
            self.instruction, self.inside = None, None
            self._clear_slots()
            self.prev_state = BROKEN
            self.step, self.deadline = OUT_STEP, self.down[1] + self.host.config.broken
            self._emit(E.ATTENTION, reason, team=self.team, machine=self.name,
                           time_to_show=10.0)
            self._emit(E.MACHINE, f"{self.name} reset while DOWN: {reason}", team=self.team,
                           machine=self.name, state=DOWN, previous=DOWN, reason=reason,
                           cause="reset", broken=True)
            return
        self.break_(reason, "reset")

    def set_lights(self, want: dict) -> None:
        if want != self.lights:
            self.lights = dict(want)
            self.host.world.set_lights(self.name, red=want["RED"], yellow=want["YELLOW"],
                                       green=want["GREEN"])
            self._emit(E.LIGHTS, f"{self.name} lights {light_text(want)}", team=self.team,
                           machine=self.name, lights=dict(want))

    @property
    def slide_loaded(self) -> int:
        return self.bases_added - self.bases_used
