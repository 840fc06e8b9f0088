"""What a human referee would penalise, and the machines that went BROKEN.

The refbox code leaves some rules to the referee (rulebook scoring table):
a workpiece dropped on the floor (2025: -10), a workpiece put on a machine
of the other team (obstruction, -20), a machine instructed without a
workpiece placed on its input (2025: -1).  The simulated refbox applies
none of them to the score; it reports each as a ``referee`` event
(:class:`RefereeCall`, with the penalty the profile's rulebook gives, None
where it gives none), so a game's report shows what a referee would have
taken.  :func:`tally` counts them per team, with the stations that went
BROKEN by cause (the refbox's reason, as a short key) from the ``machine``
events.
"""
from __future__ import annotations

from dataclasses import dataclass

from rll_bt.contracts import Tally

from . import events as E

DROPPED, OBSTRUCTION, UNFED = "dropped-workpiece", "obstruction", "prepare-without-workpiece"
CALLS = (DROPPED, OBSTRUCTION, UNFED)


@dataclass(frozen=True)
class RefereeCall:
    """One thing a referee would penalise: ``what`` (one of :data:`CALLS`), the ``team``
    that did it, the ``machine`` concerned, the rulebook's ``penalty`` (None: none in
    this rule set) and a human ``text``."""

    what: str
    team: str | None
    machine: str | None
    penalty: int | None
    text: str


def call(profile, what: str, text: str, team: str | None, machine: str | None = None,
         **data) -> tuple[str, dict]:
    """The ``referee`` event's text and data for a :class:`RefereeCall`."""
    if what not in CALLS:
        raise ValueError(f"unknown referee call {what!r} (known: {', '.join(CALLS)})")
    penalty = profile.referee_penalties.get(what)
    shown = f"{text} (referee: {penalty:+d})" if penalty is not None else text
    return shown, dict(data, what=what, penalty=penalty)


def breakdowns(events, team: str) -> dict[str, int]:
    """``team``'s stations that went BROKEN, counted by cause."""
    out: dict[str, int] = {}
    for ev in events:
        if ev.kind != E.MACHINE or ev.team != team:
            continue
        if ev.data.get("state") == "BROKEN" or ev.data.get("broken"):
            cause = ev.data.get("cause", "other")
            out[cause] = out.get(cause, 0) + 1
    return dict(sorted(out.items()))


def referee_calls(events, team: str) -> dict[str, dict]:
    """``team``'s referee calls by kind: {"count": n, "penalty": total points}."""
    out: dict[str, dict] = {}
    for ev in events:
        if ev.kind != E.REFEREE or ev.team != team:
            continue
        what = ev.data["what"]
        row = out.setdefault(what, {"count": 0, "penalty": 0})
        row["count"] += 1
        row["penalty"] += ev.data.get("penalty") or 0
    return dict(sorted(out.items()))


def tally(events, team: str) -> Tally:
    """``team``'s stations gone BROKEN by cause and its referee calls."""
    return Tally(breakdowns(events, team), referee_calls(events, team))
