"""The plug-in contracts of a game: what games find through entry points.

- :mod:`.world`: :class:`World`, the field, its robots and stations on one
  clock (step, a robot's backend, its true pose, collisions);
- :mod:`.refbox`: :class:`RefboxView`, the referee box's game read-only
  (status, awards, deliveries, stations, orders, the tally of stations broken
  and referee calls, and their types), and
  :class:`SimulatedRefbox` (with :class:`InProcessRefbox`,
  :class:`RefboxProcess`): what the host of a simulated game does with it;
- :mod:`.simulation`: the simulator (``rll_bt.simulators``), a world and
  its refbox;
- :mod:`.teamserver`: an in-process team server (``rll_bt.teamservers``).

A robot's own contract is :mod:`rll_bt.backend` (``rll_bt.backends``).
"""
from .refbox import (
    Award,
    Delivery,
    GameStatus,
    InProcessRefbox,
    RefboxProcess,
    RefboxView,
    SimulatedRefbox,
    StationTruth,
    Tally,
)
from .simulation import SIMULATORS, Simulation, SimulatorFactory, load_simulator
from .teamserver import (
    TEAMSERVERS,
    TeamServerFactory,
    TeamServerHandle,
    TeamServerOptions,
    check_teamserver,
    load_teamserver,
)
from .world import World

__all__ = ["Award", "Delivery", "GameStatus", "StationTruth", "Tally", "RefboxView", "SimulatedRefbox",
           "InProcessRefbox", "RefboxProcess", "World", "SIMULATORS", "Simulation", "SimulatorFactory",
           "load_simulator",
           "TEAMSERVERS", "TeamServerFactory", "TeamServerHandle", "TeamServerOptions", "load_teamserver",
           "check_teamserver"]
