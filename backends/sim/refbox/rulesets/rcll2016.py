"""What differs between rule sets inside the game core, behind one object.

The package (:func:`~backends.sim.refbox.rulesets.rules_for`) picks the rule
set of a profile.  The game core asks it
for the phase sequence, the exploration model and when reports are taken,
the signal-tower lights of a station, the order schedule, PrepareMachine
checks, the delivery judgement and the down periods, and nothing else in the
core names a year.  :class:`Rules2016` is the 2016 refbox (tag 2016-1);
:class:`~.rcll2025.Rules2025` today's (HEAD) refbox, a subclass that
overrides what changed.
"""
from __future__ import annotations

import random

from rll_bt.rules import CYAN, machine_type, mirror_machine_name

from ..exploration2016 import Exploration2016
from ..orders2016 import judge_delivery_2016, schedule_2016
from ..timing import EXPLORATION, PRODUCTION, SETUP


class Rules2016:
    """The 2016 rules (refbox tag 2016-1)."""

    name = "rcll2016"
    sends_exploration_info = True       # ExplorationInfo (light codes, zones) on public
    missing_instruction_breaks = True   # a PrepareMachine without instruction breaks the station
    prepare_timeout: float | None = None   # PrepareMachine.sent_at older than this is ignored
    processing_from_input = True        # PROCESSING once the workpiece is on the input (the PLC)
    ds_waits_for_window = False         # the DS delivers whenever its workpiece comes
    slide_counts_while_broken = True    # bases put on a BROKEN RS still score (then are cleared)

    # -- phases ------------------------------------------------------------------
    def has_phase(self, phase: str) -> bool:
        """Whether the operator may switch to ``phase``."""
        return True

    def phase_sequence(self, timing) -> tuple[str, ...]:
        """Phases after PRE_GAME, in order, before POST_GAME."""
        return (SETUP, EXPLORATION, PRODUCTION) if timing.exploration > 0 else (SETUP, PRODUCTION)

    def training_start(self, timing) -> str:
        """The phase a game without team names starts in (a training game)."""
        return EXPLORATION if timing.exploration > 0 else PRODUCTION

    def checkpoints(self, game) -> list[float]:
        """Game times in the current phase at which :meth:`update` must run exactly."""
        return []

    def update(self, game) -> None:
        """What follows game time in PRODUCTION beyond stations and orders."""

    # -- exploration ---------------------------------------------------------------
    def exploring(self, game) -> bool:
        """Whether MachineReports are taken (and MachineReportInfo is sent) now."""
        return game.phase == EXPLORATION

    def make_exploration(self, profile, layout, rng: random.Random,
                         feedback_time: float = 5.0) -> Exploration2016:
        zones = {m: p.zone for m, p in layout.machines.items()}
        return Exploration2016(profile, zones, rng, feedback_time)

    def on_report(self, game, judgement) -> None:
        """A report entry was judged: blink its machine green/red for the feedback time."""
        if judgement.feedback and judgement.machine in game.stations:
            game.feedback_until[judgement.machine] = (game.game_time
                                                      + game.exploration.feedback_time)
            game.show_exploration_lights(judgement.machine)

    def station_lights(self, game, station) -> dict:
        """The tower ``station`` shows in PRODUCTION: its state's lights."""
        return station.state_lights()

    # -- production ----------------------------------------------------------------
    def refuse_prepare(self, game, station) -> str | None:
        """Why a PrepareMachine for ``station`` of the sender is refused (with an attention
        message), or None.  Profiles with ``prepare_requires_report`` (2025) refuse
        stations not yet correctly reported."""
        if game.profile.prepare_requires_report and \
                not game.exploration.correctly_reported(station.team, station.name):
            return f"{station.name} is not yet correctly reported"
        return None

    def stale_prepare(self, game, sent_at: float | None) -> str | None:
        """Why a PrepareMachine sent at ``sent_at`` (Unix s) is too old, or None."""
        if self.prepare_timeout is None or sent_at is None:
            return None
        age = game.clock.epoch() - float(sent_at)
        if age > self.prepare_timeout:
            return f"sent {age:.0f} s ago (more than {self.prepare_timeout:.0f} s)"
        return None

    def prepare_busy(self, game, station) -> str:
        """A PrepareMachine for a station that is not IDLE: ignored."""
        return f"ignored: {station.name} is {station.state}"

    def validate_ds(self, game, instr) -> str | None:
        """Why a DS instruction breaks the station, or None: 2016 takes a gate 0-3."""
        if not 0 <= int(instr.gate) <= 3:
            return f"with invalid delivery gate {instr.gate}"
        return None

    def delivery_gate(self, game, instr) -> int:
        """The gate a prepared DS delivers to: the instructed one (2016)."""
        return int(instr.gate)

    def make_orders(self, profile, rng: random.Random, timing, ring_costs: dict[str, int]):
        return schedule_2016(profile, rng, timing)

    def judge_delivery(self, profile, orders, team, wp, gate, t, ring_costs, order_id=None):
        return judge_delivery_2016(profile, orders, team, wp, gate, t, ring_costs)

    def down_periods(self, profile, rng: random.Random, timing) -> dict[str, tuple[float, float]]:
        """One random RS and one random CS per team go down for a while; the magenta
        twin of the chosen cyan machine goes down at the same time (mirrored), as
        machines.clp draws it: length U{lo..hi} s of the profile's ``down_period``,
        start U{first .. P - length} over the whole production (2016: first 1 s).
        A shorter production scales both with it."""
        P, scale = float(timing.production), timing.production_scale
        lo, hi = (int(v) for v in profile.down_period)
        first = self.down_first(profile, timing)
        out = {}
        for kind in ("RS", "CS"):
            names = sorted(m for m in profile.machines(CYAN) if machine_type(m) == kind)
            if not names or P <= 0:
                continue
            m = rng.choice(names)
            length = rng.randint(lo, hi) * scale
            span = max(0.0, P - length - first)
            start = first + rng.randint(0, int(span / scale)) * scale
            out[m] = out[mirror_machine_name(m)] = (start, start + length)
        return out

    def down_first(self, profile, timing) -> float:
        """Earliest start of a down period, game seconds."""
        return float(profile.down_start) * timing.production_scale
