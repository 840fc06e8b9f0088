"""The simulator contract: a world and the simulated refbox that plays on it.

Games never import a simulator by name: they find it through the entry
point group ``rll_bt.simulators``, a factory called as ``factory(profile=...,
seed=..., team_name=..., key=..., perception=..., gui=..., phases={...},
world_step=..., robot_options={...}, refbox="here" | "process",
stored_game=None | path, save_game=None | path)`` that
returns a :class:`Simulation`: a :class:`~.world.World` and its refbox, an
:class:`~.refbox.InProcessRefbox` on the world's clock (``"here"``, a
lockstep game) or a :class:`~.refbox.RefboxProcess` (``"process"``,
``rll-bt sim --processes``: the simulation holds the world only, gives the
refbox process's command line and reads the game from what it writes).
``phases`` overrides phase lengths in game seconds (``{"setup": 10}``),
``robot_options`` apply to every robot.  ``stored_game``: a stored game's
file whose field, orders and the rest the game plays instead of drawing
them from the seed (:class:`~rll_bt.errors.UserError` when it cannot be read
or is of another profile); ``save_game``: where the refbox writes its game in that form.  The factory publishes its
perception modes as ``choices["perception"]`` (:func:`rll_bt.plugins.offers`).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .refbox import SimulatedRefbox
from .world import World

SIMULATORS = "rll_bt.simulators"


@dataclass
class Simulation:
    """What a simulator's factory returns: ``world`` and its ``refbox``."""

    world: World
    refbox: SimulatedRefbox

    def close(self) -> None:
        """The refbox first (it may still talk to the world), then the world."""
        try:
            self.refbox.close()
        finally:
            self.world.close()


SimulatorFactory = Callable[..., Simulation]


def load_simulator(name: str) -> SimulatorFactory:
    """The ``rll_bt.simulators`` entry point ``name``; KeyError names the installed ones."""
    from .. import plugins
    return plugins.load(SIMULATORS, name)
