"""What happened in a game, as a flat log of events.

The game core appends an :class:`Event` for every phase or state change,
award, machine state change, robot seen or lost, order activation, report,
delivery, attention message and referee call (:mod:`.referee`).  The network node turns ``attention``
events into AttentionMessages and ``machine`` events into an immediate
MachineInfo; the CLI prints ``phase`` and ``points`` events; tests read them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

PHASE = "phase"            # phase switched (data: previous)
STATE = "state"            # game state switched (data: previous)
POINTS = "points"          # an award (points, team; data: order)
ATTENTION = "attention"    # an AttentionMessage to show (team None = everyone; data: time_to_show)
MACHINE = "machine"        # a station changed state (data: state, previous, reason)
LIGHTS = "lights"          # a station's signal tower changed (data: lights)
ROBOT = "robot"            # a robot appeared, was lost or came back (data: number, name, what)
ORDER = "order"            # an order became active (data: id)
REPORT = "report"          # an exploration report entry was judged (data: type_ok, zone_ok)
DELIVERY = "delivery"      # the DS consumed a workpiece (data: order, how)
WORKPIECE = "workpiece"    # a station spawned, changed or consumed a workpiece
REFEREE = "referee"        # what a human referee would penalise (data: what, penalty)
KINDS = (PHASE, STATE, POINTS, ATTENTION, MACHINE, LIGHTS, ROBOT, ORDER, REPORT, DELIVERY,
         WORKPIECE, REFEREE)


@dataclass(frozen=True)
class Event:
    """``kind`` (one of :data:`KINDS`), a human ``text``, the ``phase`` and
    ``game_time`` (game seconds into that phase) it happened at, and optionally
    the ``team`` ("CYAN"/"MAGENTA"), ``machine``, ``points`` and extra ``data``."""

    kind: str
    text: str
    phase: str
    game_time: float
    team: str | None = None
    machine: str | None = None
    points: int | None = None
    data: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return f"[{self.phase} {self.game_time:7.1f}] {self.kind}: {self.text}"
