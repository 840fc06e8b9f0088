"""What a robot did at a station, as the world reports it (slot events), applied to the
game: a put or take goes to the station; a workpiece put on a machine of the
other team, or dropped on the floor, is a referee call (:mod:`.referee`).
"""
from __future__ import annotations

import logging

from . import referee
from .world import DROP, PUT, TAKE, WorldLost

log = logging.getLogger("backends.sim.refbox")


def apply(game, ev) -> None:
    """Apply one :class:`~.world.SlotEvent` to ``game`` (a :class:`~.game.RefboxGame`)."""
    robot = getattr(ev, "robot", None)
    team = str(robot[0]).upper() if robot else None
    who = f"robot {robot[1]} of {team}" if robot else "a robot"
    try:
        if ev.kind == DROP:
            game.referee(referee.DROPPED, f"{who} dropped {ev.workpiece} on the floor", team=team)
            return
        st = game.stations.get(ev.machine)
        if st is None:
            return
        if ev.kind == PUT:
            if team is not None and team != st.team:
                game.referee(referee.OBSTRUCTION, f"{who} put {ev.workpiece} on {st.name} of "
                             "the other team", team=team, machine=st.name)
            st.on_put(ev.slot, ev.workpiece, robot)
        elif ev.kind == TAKE:
            st.on_take(ev.slot, ev.workpiece)
    except WorldLost:
        raise
    except Exception:
        log.exception("slot event %s failed", ev)
