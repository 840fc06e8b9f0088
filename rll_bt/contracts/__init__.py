"""The plug-in contracts of a game: what games find through entry points.

- :mod:`.simulation`: the simulator (``rll_bt.simulators``), its world and
  its simulated refbox;
- :mod:`.refbox`: what a game reads of the refbox (:class:`GameStatus`,
  :class:`Award`, :class:`Delivery`, :class:`StationTruth`);
- :mod:`.teamserver`: an in-process team server (``rll_bt.teamservers``).

The robot's own contract is :mod:`rll_bt.backend` (``rll_bt.backends``).
"""
from .refbox import Award, Delivery, GameStatus, StationTruth
from .simulation import SIMULATORS, Simulation, SimulatorFactory, load_simulator
from .teamserver import TEAMSERVERS, TeamServerFactory, TeamServerHandle, TeamServerOptions, load_teamserver

__all__ = ["Award", "Delivery", "GameStatus", "StationTruth", "SIMULATORS", "Simulation", "SimulatorFactory",
           "load_simulator", "TEAMSERVERS", "TeamServerFactory", "TeamServerHandle", "TeamServerOptions",
           "load_teamserver"]
