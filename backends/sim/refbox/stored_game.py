"""A stored game played by the simulated refbox, and a game stored from it.

What the refbox draws at random for a game (``rngs`` of
:class:`~.game.RefboxGame`: ring colours and costs, orders, down periods)
enters a game from a :class:`~backends.sim.stored.StoredGame` the way the
drawn values do: :func:`play_stored` replaces them on a game that has not
started, so they go through the same game core (order activation, windows,
scoring, down periods) as drawn ones.  The field comes with the world: a
world built from ``stored.layout()`` (``World(..., layout=...)``), which
:func:`play_stored` checks.  :func:`store_game` is the other way: the
game's field (with each station's exact centre), orders, ring setup and
down periods as a stored game (``rll-bt sim --save-game``).

Times stay as stored: production game seconds of the game it was stored
from (a refbox game report's are a 1200 s production), whatever the
phase lengths of the game playing it.  A 2016 game's light codes and type
strings are not stored; they follow the seed.
"""
from __future__ import annotations

from rll_bt.rules import machine_type

from ..stored import StoredGame, StoredOrder
from .orders2016 import Order


def _order(o: StoredOrder) -> Order:
    return Order(id=o.id, complexity=int(o.complexity[1:]), base=o.base, rings=tuple(o.rings), cap=o.cap,
                 quantity=o.quantity, gate=o.gate, begin=int(o.delivery[0]), end=int(o.delivery[1]),
                 activate_at=int(o.activate_at), standing=o.standing, overtime=o.overtime,
                 competitive=o.competitive)


def play_stored(game, stored: StoredGame) -> None:
    """Let ``game`` (a :class:`~.game.RefboxGame` before it started) play
    ``stored``: its orders, ring colours and costs and down periods.
    ValueError when the game plays another profile, has started, or its
    world's field is not the stored one."""
    if stored.profile != game.profile.name:
        raise ValueError(f"the stored game is {stored.profile}, the refbox plays {game.profile.name}")
    if game.phase != "PRE_GAME":
        raise ValueError(f"a stored game is played from the start, not in {game.phase}")
    prof = game.profile
    for m, (zone, rot) in sorted(stored.machines.items()):
        if m not in game.layout.machines:
            raise ValueError(f"the stored game has {m}, the world has not")
        here = game.layout[m]
        if (here.zone, here.rotation_deg % 360) != (prof.zone_number(zone), rot % 360):
            raise ValueError(f"{m} stands in {prof.zone_name(here.zone)} at {here.rotation_deg} deg, "
                             f"the stored game has it in {zone} at {rot} deg: build the world from the "
                             f"stored game's field")
    if stored.ring_colors:
        colours = {machine_type_key(m): tuple(c) for m, c in stored.ring_colors.items()}
        game._rs_colors.update(colours)
    if stored.ring_costs:
        game.ring_costs = dict(stored.ring_costs)
    if stored.orders:
        game.orders = [_order(o) for o in stored.orders]
    for st in game.stations.values():
        st.down, st.down_done = None, False
    for m, period in stored.down_periods.items():
        if m in game.stations:
            game.stations[m].down = (float(period[0]), float(period[1]))


def machine_type_key(machine: str) -> str:
    """The key of the refbox's per-type tables ("C-RS1" -> "RS1")."""
    return machine.split("-", 1)[1]


def store_game(game, name: str = "") -> StoredGame:
    """The stored form of ``game`` (a :class:`~.game.RefboxGame`): the field
    of its world (zone, rotation and centre of every station), its orders,
    ring colours and costs and down periods."""
    prof = game.profile
    machines, poses = {}, {}
    for m, pl in game.layout.machines.items():       # in the field's order, as the world builds it
        machines[m] = (prof.zone_name(pl.zone), int(pl.rotation_deg) % 360)
        poses[m] = (float(pl.pose.x), float(pl.pose.y))
    orders = tuple(StoredOrder(o.id, f"C{o.complexity}", o.base, tuple(o.rings), o.cap, o.quantity,
                               (int(o.begin), int(o.end)), o.gate, int(o.activate_at), bool(o.competitive),
                               bool(o.standing), bool(o.overtime)) for o in game.orders)
    colours = {m: tuple(game.rs_colors(m)) for m in sorted(game.stations)
               if machine_type(m) == "RS" and len(game.rs_colors(m)) >= 2}
    downs = {m: (float(st.down[0]), float(st.down[1])) for m, st in sorted(game.stations.items())
             if st.down is not None}
    stored = StoredGame(prof.name, machines, orders, dict(game.ring_costs), colours, downs,
                        name or f"rll-bt {prof.name} seed {game.seed}", poses)
    stored.check()
    return stored


__all__ = ["play_stored", "store_game"]
