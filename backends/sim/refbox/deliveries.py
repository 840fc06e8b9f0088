"""Deliveries: what the DS consumed, judged by the rule set (at once, or once the
simulated referee confirms it, ``StationConfig.delivery_confirm`` game seconds later).

The game owns one :class:`Deliveries` (``game.deliveries``); its DS stations
hand it each consumed workpiece through ``game.deliver``, and the game calls
:meth:`Deliveries.confirm_due` as game time passes.  Judging awards the
points the rule set gives (:mod:`.orders2016`, :mod:`.orders2025`) and emits
a ``delivery`` event (and an attention message where the refbox sends one).
"""
from __future__ import annotations

from dataclasses import dataclass

from . import events as E
from .world import Workpiece


@dataclass(frozen=True)
class PendingDelivery:
    """A delivery the referee has not confirmed yet (OrderInfo ``unconfirmed_deliveries``):
    delivery ``id``, ``team``, the DS ``machine``, the ``order`` it was prepared for, the
    workpiece, the production ``game_time`` it was delivered at and the game time the
    referee confirms it (``confirm_at``)."""

    id: int
    team: str
    machine: str
    order: int | None
    workpiece: Workpiece
    gate: int
    game_time: float
    confirm_at: float


class Deliveries:
    """The deliveries of ``game`` (a :class:`~.game.RefboxGame`: its rules, profile,
    orders, ring costs, config, clock-free ``game_time``, ``award`` and ``emit``)."""

    def __init__(self, game):
        self.game = game
        self.pending: list[PendingDelivery] = []
        self._ids = 0

    def deliver(self, station, wp: Workpiece, gate: int, game_time: float) -> None:
        """The DS ``station`` consumed ``wp``: judge it now, or list it as unconfirmed for
        ``config.delivery_confirm`` game seconds first."""
        g = self.game
        self._ids += 1
        d = PendingDelivery(self._ids, station.team, station.name,
                            getattr(station.instruction, "order_id", None), wp, gate, game_time,
                            game_time + g.config.delivery_confirm)
        if g.config.delivery_confirm > 0:
            self.pending.append(d)
            g.emit(E.DELIVERY, f"{d.team} delivered {wp} (delivery {d.id}, unconfirmed)",
                   team=d.team, machine=d.machine, game_time=game_time, order=d.order,
                   how="unconfirmed", workpiece=wp, delivery=d.id)
            return
        self.judge(d)

    def judge(self, d: PendingDelivery) -> None:
        g = self.game
        res = g.rules.judge_delivery(g.profile, g.orders, d.team, d.workpiece, d.gate,
                                     d.game_time, g.ring_costs, d.order)
        for pts, reason in res.awards:
            g.award(d.team, pts, reason, machine=d.machine, game_time=d.game_time,
                    order=res.order)
        g.emit(E.DELIVERY, f"{d.team} delivered {d.workpiece} at gate {d.gate}: {res.how}",
               team=d.team, machine=d.machine, game_time=d.game_time,
               points=res.points, order=res.order, how=res.how, workpiece=d.workpiece,
               delivery=d.id)
        if res.attention:
            g.emit(E.ATTENTION, res.attention, team=d.team, time_to_show=10.0)

    def confirm_due(self) -> None:
        """Judge every pending delivery whose confirmation time has come."""
        due = [d for d in self.pending if d.confirm_at <= self.game.game_time]
        for d in due:
            self.pending.remove(d)
            self.judge(d)
