"""Recovering a lost pose: spread the particles and look around.

:class:`Relocalise` re-initialises the localiser around its last estimate
(or over the whole field with ``global_search``), then turns the robot on
the spot (at most one full turn) while the filter updates, and succeeds as
soon as the confidence reaches the localiser's ``confident`` level.  If a
full turn does not do it, it fails with LOCALISATION_LOST.
"""
from __future__ import annotations

import math

from ..activity import Activity, Status
from ..errors import SkillError, SkillFailure
from ..navigation.motions import Turn


class Relocalise(Activity):
    name = "relocalise"

    def __init__(self, ctx, spread: tuple[float, float, float] = (0.5, 0.5, 0.6),
                 global_search: bool = False, timeout: float | None = 30.0):
        super().__init__(ctx, timeout)
        self.spread = spread
        self.global_search = global_search
        self.turn: Turn | None = None

    def _on_start(self) -> None:
        loc = self.ctx.pose_source
        if not hasattr(loc, "filter"):
            raise SkillFailure(SkillError.LOCALISATION_LOST, "the pose source cannot relocalise")
        if self.global_search or loc.pose() is None:
            loc.initialise_global()
        else:
            loc.initialise(loc.pose(), self.spread)
        self.turn = Turn(self.ctx, by=2.0 * math.pi, omega=0.5).start()

    def _step(self, now: float) -> Status:
        loc = self.ctx.pose_source
        loc.update(force=True)
        if loc.confidence >= loc.config.confident:
            self.message = f"relocalised, confidence {loc.confidence:.2f}"
            return Status.SUCCESS
        if self.turn.poll() is not Status.RUNNING:
            raise SkillFailure(SkillError.LOCALISATION_LOST,
                               f"still lost after a full turn (confidence {loc.confidence:.2f})")
        return Status.RUNNING

    def _on_stop(self, status: Status) -> None:
        if self.turn is not None and self.turn.status is Status.RUNNING:
            self.turn.cancel()
        self.ctx.stop_base()
