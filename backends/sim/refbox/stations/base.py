"""Station state machines of the production phase (the refbox's production.clp).

States and signal-tower lights (refbox code; where the 2016 rulebook's
wording differs, e.g. "yellow busy", the code wins):

================  =============================  =================================
state             lights 2016 (2017+ if other)   leaves when
================  =============================  =================================
IDLE              green                          a valid PrepareMachine arrives
PREPARED          green blinking for 3 s, green  a workpiece lies on the input
                  (green blinking)
PROCESSING        green + yellow                 the processing time has passed
READY-AT-OUTPUT   yellow (yellow + green blink)  a robot takes the product
WAIT-IDLE         yellow blinking (yellow and    5 s later -> IDLE
                  green blinking)
BROKEN            red + yellow blinking          30 s later -> IDLE (slots cleared)
DOWN              red                            the down period ends
================  =============================  =================================

Which table a station shows is the rule set's choice (``host.station_lights``):
2017+ stations show their state only once correctly reported.

A wrong or missing instruction breaks the station: an RS ring colour the RS
does not have, RETRIEVE_CAP while a cap is buffered, MOUNT_CAP without one,
a workpiece fed to an RS without enough additional bases on the slide, a
workpiece the operation cannot work on (RETRIEVE from a cap-less one, MOUNT
on a capped one, a ring on a capped or three-ring one), more than 3 bases
loaded on a slide.  Each break sends an attention message with the reason.
A DOWN period freezes the station's timers and restores its state after.

Products: the BS dispenses a base of the instructed colour on the instructed
side; the RS mounts a ring on the workpiece fed at the input (consuming the
ring's cost in slide bases) and puts it on the output; the CS takes the cap
off a capped workpiece into its buffer (the cap-less base appears at the
output) or mounts the buffered cap; the DS consumes the workpiece and has
the game score the delivery.  Additional bases put on an RS slide are
consumed and score +2 each (up to 3 loaded).  Times are game seconds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from .. import events as E
from ..world import ALL_OFF, BLINK, INPUT, ON, OUTPUT, Workpiece, describe, lights, station_slots

IDLE, PREPARED, PROCESSING = "IDLE", "PREPARED", "PROCESSING"
READY_AT_OUTPUT, WAIT_IDLE, BROKEN, DOWN = "READY-AT-OUTPUT", "WAIT-IDLE", "BROKEN", "DOWN"
STATES = (IDLE, PREPARED, PROCESSING, READY_AT_OUTPUT, WAIT_IDLE, BROKEN, DOWN)

STATE_LIGHTS = {
    IDLE: lights(green=ON),
    PREPARED: lights(green=ON),
    PROCESSING: lights(yellow=ON, green=ON),
    READY_AT_OUTPUT: lights(yellow=ON),
    WAIT_IDLE: lights(yellow=BLINK),
    BROKEN: lights(red=BLINK, yellow=BLINK),
    DOWN: lights(red=ON),
}
PREPARED_BLINK = lights(green=BLINK)
#: machine-lights.clp (2019+)
STATE_LIGHTS_2025 = {
    IDLE: lights(green=ON),
    PREPARED: lights(green=BLINK),
    PROCESSING: lights(yellow=ON, green=ON),
    READY_AT_OUTPUT: lights(yellow=ON, green=BLINK),
    WAIT_IDLE: lights(yellow=BLINK, green=BLINK),
    BROKEN: lights(red=BLINK, yellow=BLINK),
    DOWN: lights(red=ON),
}


@dataclass(frozen=True)
class StationConfig:
    """Processing durations and station rules, game seconds.

    Durations are our choice for a plausible game (a real MPS takes a few
    to twenty seconds); the other values are the refbox's globals.clp.
    """

    bs_dispense: float = 5.0
    rs_mount: float = 15.0
    cs_process: float = 12.0
    ds_deliver: float = 8.0
    ss_process: float = 10.0               # storage station store / retrieve
    prepared_blink: float = 3.0            # PREPARED-BLINK-TIME
    wait_idle: float = 5.0                 # RETRIEVE-WAIT-IDLE-TIME
    broken: float = 30.0                   # BROKEN-DOWN-TIME
    prepared_timeout: float | None = None  # break a PREPARED station never fed (None: never)
    slide_max: int = 3                     # LOADED-WITH-MAX
    cs_caps: tuple[tuple[str, str], ...] = (("CS1", "CAP_GREY"), ("CS2", "CAP_BLACK"))
    carrier_base: str = "BASE_RED"         # base under the caps on a CS shelf
    refill_shelf: bool = True              # a taken cap carrier is replaced at once
    delivery_confirm: float = 0.0          # 2017+: game s until the referee confirms a delivery

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
    def award(self, team: str, points: int, reason: str, machine: str | None = None,
              game_time: float | None = None) -> None: ...
    def emit(self, kind: str, text: str, *, team: str | None = None, machine: str | None = None,
             game_time: float | None = None, **data) -> None: ...
    def deliver(self, station: Station, wp: Workpiece, gate: int, game_time: float) -> None: ...
    def station_state_changed(self, station: Station, previous: str) -> None: ...


@dataclass
class Station:
    """One station's production state.  ``now`` is the station's game time
    (production seconds) as of its last :meth:`update`."""

    name: str
    team: str
    host: StationHost
    state: str = IDLE
    prev_state: str | None = None
    lights: dict = field(default_factory=lambda: dict(ALL_OFF))
    now: float = 0.0
    active: bool = False
    deadline: float | None = None
    blink_until: float | None = None
    down: tuple[float, float] | None = None
    down_done: bool = False
    broken_reason: str = ""
    instruction: object = None
    input_wp: Workpiece | None = None
    inside: Workpiece | None = None
    out_slot: str = OUTPUT
    bases_added: int = 0
    bases_used: int = 0
    cap_buffer: str | None = None

    kind = "?"
    duration_key = ""

    # -- phase ----------------------------------------------------------------
    def start_production(self, game_time: float) -> None:
        """Enter production: IDLE with its lights."""
        self.active, self.now = True, game_time
        self._set_state(IDLE, "production started")

    def stop_production(self) -> None:
        self.active = False

    # -- inputs ------------------------------------------------------------------
    def prepare(self, instr) -> None:
        """A PrepareMachine for this (IDLE) station; the game checked phase, team and state."""
        reason = self.validate(instr)
        if reason:
            self.break_(reason)
            return
        self.instruction = instr
        self.blink_until = self.now + self.host.config.prepared_blink
        self._set_state(PREPARED, f"prepared: {instr}")
        cfg = self.host.config
        self.deadline = self.now + cfg.prepared_timeout if cfg.prepared_timeout else None
        self.on_prepared()
        self._maybe_start()

    def on_put(self, slot: str, wp) -> None:
        if slot == INPUT:
            self.input_wp = describe(wp)
            self._maybe_start()

    def feed(self, wp: Workpiece) -> None:
        """A workpiece fed to the input without a world (mockup mode): processed at once
        when the station is PREPARED, else kept until it is."""
        self.input_wp = wp
        self._maybe_start()

    def on_take(self, slot: str, wp: Workpiece | None) -> None:
        if slot == INPUT:
            self.input_wp = None
        if slot != self.out_slot or self.inside is not None:
            return
        if self.state == READY_AT_OUTPUT:
            self._product_taken()
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
        return None

    def on_prepared(self) -> None:
        pass

    def start(self, wp: Workpiece) -> str | None:
        """Begin processing ``wp`` (taken off the input); a reason to break instead."""
        return None

    def finish(self) -> None:
        raise NotImplementedError

    @property
    def duration(self) -> float:
        return getattr(self.host.config, self.duration_key)

    # -- machinery ---------------------------------------------------------------
    def break_(self, reason: str) -> None:
        self.broken_reason = f"{self.name}: {reason}"
        self.instruction, self.inside = None, None
        self._clear_slots()
        self._set_state(BROKEN, reason)
        self.deadline = self.now + self.host.config.broken
        self.host.emit(E.ATTENTION, self.broken_reason, team=self.team, machine=self.name,
                       time_to_show=10.0)

    def _maybe_start(self) -> None:
        if (self.active and self.state == PREPARED and self.input_wp is not None
                and self.kind != "BS"):
            taken = self.host.world.remove_workpiece(self.name, INPUT)
            wp = describe(taken) if taken is not None else self.input_wp
            self.input_wp = None
            reason = self.start(wp)
            if reason:
                self.break_(reason)
                return
            self.inside = wp
            self._processing()

    def _processing(self) -> None:
        self._set_state(PROCESSING, f"processing {self.instruction}")
        self.deadline = self.now + self.duration

    def _ready(self, wp: Workpiece, slot: str = OUTPUT) -> None:
        self.out_slot = slot
        self.host.world.spawn_workpiece(self.name, slot, wp.base, tuple(wp.rings), wp.cap)
        self.host.emit(E.WORKPIECE, f"{self.name} put {wp} on {slot}", team=self.team,
                       machine=self.name, workpiece=wp, slot=slot)
        self.inside = None
        self.deadline = None
        self._set_state(READY_AT_OUTPUT, f"{wp} ready at {slot}")

    def _product_taken(self) -> None:
        wait = self.host.config.wait_idle
        if wait > 0:
            self._set_state(WAIT_IDLE, "product taken")
            self.deadline = self.now + wait
        else:
            self._idle("product taken")

    def _idle(self, why: str) -> None:
        self.instruction, self.deadline = None, None
        self._set_state(IDLE, why)

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
                cand.append((self.deadline, self._deadline))
        if not cand:
            return None, None
        return min(cand, key=lambda c: c[0])

    def _blink_end(self) -> None:
        self.blink_until = None
        self._show_lights()

    def _deadline(self) -> None:
        self.deadline = None
        if self.state == PROCESSING:
            self.finish()
        elif self.state == WAIT_IDLE:
            self._idle("retrieval done")
        elif self.state == BROKEN:
            self._recover()
        elif self.state == PREPARED:
            self.break_("prepared, but no workpiece fed in time")

    def _recover(self) -> None:
        self.bases_used = self.bases_added
        self.cap_buffer = None
        self._clear_slots()
        self.broken_reason = ""
        self._idle("recovered")

    def _down_start(self) -> None:
        start, end = self.down
        self.down_done = True
        length = end - start
        if self.deadline is not None:
            self.deadline += length
        if self.blink_until is not None:
            self.blink_until += length
        self.prev_state = self.state
        self._set_state(DOWN, f"down for {length:.0f} s")

    def _down_end(self) -> None:
        back = self.prev_state or IDLE
        self.prev_state = None
        self._set_state(back, "up again")

    def _clear_slots(self) -> None:
        for slot in (INPUT, OUTPUT):
            if slot in station_slots(self.name) and \
                    self.host.world.workpiece_at(self.name, slot) is not None:
                self.host.world.remove_workpiece(self.name, slot)
        self.input_wp = None

    def _set_state(self, state: str, why: str) -> None:
        prev, self.state = self.state, state
        if state != PREPARED:
            self.blink_until = None
        self._show_lights()
        self.host.emit(E.MACHINE, f"{self.name} {prev} -> {state}: {why}", team=self.team,
                       machine=self.name, state=state, previous=prev, reason=why)
        self.host.station_state_changed(self, prev)

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
            self.broken_reason = f"{self.name}: {reason}"
            self.instruction, self.inside = None, None
            self._clear_slots()
            self.prev_state = BROKEN
            self.deadline = self.down[1] + self.host.config.broken
            self.host.emit(E.ATTENTION, self.broken_reason, team=self.team, machine=self.name,
                           time_to_show=10.0)
            return
        self.break_(reason)

    def set_lights(self, want: dict) -> None:
        if want != self.lights:
            self.lights = dict(want)
            self.host.world.set_lights(self.name, red=want["RED"], yellow=want["YELLOW"],
                                       green=want["GREEN"])
            self.host.emit(E.LIGHTS, f"{self.name} lights {_light_text(want)}", team=self.team,
                           machine=self.name, lights=dict(want))

    @property
    def slide_loaded(self) -> int:
        return self.bases_added - self.bases_used


def _light_text(lights: dict) -> str:
    on = [f"{c}-{s}" for c, s in lights.items() if s != "OFF"]
    return " ".join(on) or "off"
