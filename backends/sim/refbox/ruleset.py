"""What differs between rule sets inside the game core, behind one object.

:func:`rules_for` picks the rule set of a profile.  The game core asks it
for the phase sequence, the exploration model, the order schedule, the
delivery judgement and the down periods, and nothing else in the core names a
year.  ``rcll2016`` is implemented; a 2025 rule set (issue 10) adds a class
here with the same methods (exploration inside PRODUCTION, zone + rotation
reports, 2025 orders and points) and an entry in :data:`RULESETS`.
"""
from __future__ import annotations

import random

from rll_bt.rules import CYAN, machine_type, mirror_machine_name

from .exploration2016 import Exploration2016
from .orders2016 import judge_delivery_2016, schedule_2016
from .timing import EXPLORATION, PRODUCTION, SETUP


class Rules2016:
    """The 2016 rules (refbox tag 2016-1)."""

    name = "rcll2016"

    def phase_sequence(self, timing) -> tuple[str, ...]:
        """Phases after PRE_GAME, in order, before POST_GAME."""
        return (SETUP, EXPLORATION, PRODUCTION) if timing.exploration > 0 else (SETUP, PRODUCTION)

    def training_start(self, timing) -> str:
        """The phase a game without team names starts in (a training game)."""
        return EXPLORATION if timing.exploration > 0 else PRODUCTION

    def accepts_report(self, phase: str, game_time: float, timing) -> bool:
        return phase == EXPLORATION

    def make_exploration(self, profile, zones: dict[str, int], rng: random.Random,
                         feedback_time: float = 5.0) -> Exploration2016:
        return Exploration2016(profile, zones, rng, feedback_time)

    def refuse_prepare(self, game, station) -> str | None:
        """Why a PrepareMachine for an IDLE ``station`` of the sender is refused, or None.
        Profiles with ``prepare_requires_report`` (2025) refuse stations not yet
        correctly reported."""
        if game.profile.prepare_requires_report:
            rep = game.exploration.state(station.team, station.name)
            if rep is None or not rep.fully_correct:
                return f"{station.name} is not yet correctly reported"
        return None

    def make_orders(self, profile, rng: random.Random, timing):
        return schedule_2016(profile, rng, timing)

    def judge_delivery(self, profile, orders, team, wp, gate, t, ring_costs, order_id=None):
        return judge_delivery_2016(profile, orders, team, wp, gate, t, ring_costs)

    def down_periods(self, profile, rng: random.Random, timing) -> dict[str, tuple[float, float]]:
        """One random RS and one random CS per team go down for a while; the magenta
        twin of the chosen cyan machine goes down at the same time (mirrored).
        Length from the profile's ``down_period`` range, start uniform in
        [0.1 P, 0.9 P - length]; both scaled with the production length."""
        P, scale = float(timing.production), timing.production_scale
        lo, hi = profile.down_period
        out = {}
        for kind in ("RS", "CS"):
            names = sorted(m for m in profile.machines(CYAN) if machine_type(m) == kind)
            if not names or P <= 0:
                continue
            m = rng.choice(names)
            length = rng.uniform(lo, hi) * scale
            start = rng.uniform(0.1 * P, max(0.1 * P, 0.9 * P - length))
            out[m] = out[mirror_machine_name(m)] = (start, start + length)
        return out


RULESETS = {"rcll2016": Rules2016}


def rules_for(profile) -> Rules2016:
    """The rule set playing ``profile``; ValueError for a profile without one."""
    try:
        return RULESETS[profile.name]()
    except KeyError:
        raise ValueError(f"the simulated refbox does not play {profile.name!r} yet "
                         f"(it plays: {', '.join(RULESETS)})") from None
