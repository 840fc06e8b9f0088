"""A team's requests for one of its stations in PRODUCTION: PrepareMachine and
ResetMachine, checked as the refbox checks them (phase and state, the channel
it came on, a machine of that team, the rule set's own refusals) before the
station acts.  The game (:class:`~.game.RefboxGame`) calls these from
``game.prepare`` and ``game.reset_machine``.
"""
from __future__ import annotations

from rll_bt.rules import TEAMS

from . import events as E
from .timing import PRODUCTION, RUNNING


def prepare(game, team_color: str, machine: str, instruction, channel_team: str | None = None,
            *, sent_at: float | None = None) -> str:
    """A PrepareMachine: "prepared", "broken", "done" (an SS CHANGE_INFO) or
    "ignored: <why>"."""
    st = team_machine(game, "prepare", team_color, machine, channel_team)
    if isinstance(st, str):
        return st
    why = game.rules.stale_prepare(game, sent_at)
    if why:
        return f"ignored: {why}"
    why = game.rules.refuse_prepare(game, st)
    if why:
        _attention(game, team_color, f"Prepare refused: {why}")
        return f"ignored: {why}"
    if st.state != "IDLE":
        return game.rules.prepare_busy(game, st)
    if instruction is None and not game.rules.missing_instruction_breaks:
        return f"ignored: prepare for {machine} without instruction"
    st.prepare(instruction)
    if st.state == "BROKEN":
        return "broken"
    return "done" if st.state == "IDLE" else "prepared"


def reset_machine(game, team_color: str, machine: str, channel_team: str | None = None) -> str:
    """A ResetMachine: "broken" or "ignored: <why>"."""
    st = team_machine(game, "reset", team_color, machine, channel_team)
    if isinstance(st, str):
        return st
    st.reset(f"Machine {machine} resetted by the team {team_color}")
    return "broken"


def team_machine(game, what: str, team_color: str, machine: str, channel_team):
    """The station ``machine`` of ``team_color`` for a team request, or why it is
    ignored ("ignored: ..."; with the refbox's attention messages)."""
    if game.phase != PRODUCTION or game.state != RUNNING:
        return f"ignored: not in PRODUCTION/RUNNING ({game.phase}/{game.state})"
    if channel_team is not None and channel_team != team_color:
        _attention(game, channel_team, f"Invalid {what} for team {team_color} of team "
                                       f"{channel_team}")
        return "ignored: wrong channel"
    st = game.stations.get(machine)
    if st is None or st.team != team_color:
        _attention(game, team_color if team_color in TEAMS else None,
                   f"{what.capitalize()} received for invalid machine {machine}")
        return "ignored: not a machine of that team"
    return st


def _attention(game, team: str | None, text: str) -> None:
    game.emit(E.ATTENTION, text, team=team, time_to_show=10.0)
