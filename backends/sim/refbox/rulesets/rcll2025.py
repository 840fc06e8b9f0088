"""Today's rules (refbox HEAD, 2022+), as the refbox code plays them.

What changes against :class:`~.rcll2016.Rules2016`:

- phases SETUP -> PRODUCTION (+ overtime); EXPLORATION is never entered
  (the operator cannot switch to it either); the first ``exploration_time``
  game seconds of PRODUCTION (180 s) take MachineReports with zone and
  rotation (:mod:`.exploration2025`), and at that time the ground truth is
  released;
- a station shows its report feedback until it is correctly reported, then
  its production state with the 2019+ light table;
- PrepareMachine: ``sent_at`` older than 5 s is ignored; a station not yet
  correctly reported is refused (attention message) until the ground truth
  is out; one for a station that is not IDLE is ignored (READY-AT-OUTPUT
  too, since refbox commit 78b464b9); the DS takes an order id (0 =
  consume only; an unknown id breaks it) and waits for the order's window;
- a machine is PREPARED until its workpiece reached the middle of the belt
  (the 20 s rule of the profile's ``stuck_timeout`` counts from the prepare);
- bases fed into a BROKEN RS are not counted;
- orders and delivery by order id (:mod:`.orders2025`);
- down periods (30-60 s) start only after the exploration time.
"""
from __future__ import annotations

import random

from .. import events as E
from ..exploration2025 import Exploration2025
from ..orders2025 import judge_delivery_2025, schedule_2025
from ..stations import STATE_LIGHTS_2025
from ..timing import EXPLORATION, PRODUCTION, RUNNING, SETUP
from ..world import ALL_OFF
from .rcll2016 import Rules2016

PRODUCTION_PREPARE_TIMEOUT = 5.0


class Rules2025(Rules2016):
    name = "rcll2025"
    sends_exploration_info = False
    prepare_timeout = PRODUCTION_PREPARE_TIMEOUT
    processing_from_input = False
    ds_waits_for_window = True
    slide_counts_while_broken = False

    # -- phases ------------------------------------------------------------------
    def has_phase(self, phase: str) -> bool:
        return phase != EXPLORATION

    def phase_sequence(self, timing) -> tuple[str, ...]:
        return (SETUP, PRODUCTION)

    def training_start(self, timing) -> str:
        return PRODUCTION

    def checkpoints(self, game) -> list[float]:
        if game.phase == PRODUCTION and not game.exploration.released:
            return [float(game.timing.exploration_time)]
        return []

    def update(self, game) -> None:
        """Release the ground truth once the exploration time has passed."""
        ex = game.exploration
        if game.phase == PRODUCTION and not ex.released \
                and game.game_time >= game.timing.exploration_time:
            ex.release()
            game.emit(E.REPORT, "exploration time over: every machine counts as reported",
                      what="ground-truth")
            game.refresh_lights()

    # -- exploration ---------------------------------------------------------------
    def exploring(self, game) -> bool:
        return (game.phase == PRODUCTION and not game.exploration.released
                and game.game_time < game.timing.exploration_time)

    def make_exploration(self, profile, layout, rng: random.Random,
                         feedback_time: float = 5.0) -> Exploration2025:
        return Exploration2025(profile, {m: (p.zone, p.rotation_deg)
                                         for m, p in layout.machines.items()})

    def on_report(self, game, judgement) -> None:
        if judgement.machine in game.stations:
            game.refresh_lights(judgement.machine)

    def station_lights(self, game, station) -> dict:
        if game.phase != PRODUCTION or game.state != RUNNING:
            return ALL_OFF
        shown = game.exploration.report_lights(station.name)
        return shown if shown is not None else station.state_lights(STATE_LIGHTS_2025)

    # -- production ----------------------------------------------------------------
    def validate_ds(self, game, instr) -> str | None:
        if instr.order_id is None:
            return "without data"
        if instr.order_id != 0 and game.order(instr.order_id) is None:
            return "with invalid order ID"
        return None

    def delivery_gate(self, game, instr) -> int:
        """The gate comes from the order (0 when only consuming)."""
        order = game.order(instr.order_id) if instr.order_id else None
        return order.gate if order is not None else 0

    def make_orders(self, profile, rng: random.Random, timing, ring_costs: dict[str, int]):
        return schedule_2025(profile, rng, timing, ring_costs)

    def judge_delivery(self, profile, orders, team, wp, gate, t, ring_costs, order_id=None):
        return judge_delivery_2025(profile, orders, team, wp, order_id, t, ring_costs)

    def down_first(self, profile, timing) -> float:
        """After the exploration time (machines.clp: U{EXPLORATION-TIME .. P - length})."""
        return float(timing.exploration_time)
