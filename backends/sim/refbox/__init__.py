"""The simulated referee box (2016 rules; 2025 to come as a rule set).

- :class:`RefboxGame` (:mod:`.game`): the pure game core, driven by a clock.
- :class:`RefboxNode` (:mod:`.node`): the game on the wire, over UDP or the
  in-process bus.
- ``rll-bt refbox sim`` (:mod:`.cli`): a standalone refbox process.
"""
from .events import Event
from .exploration2016 import ReportEntry
from .game import RefboxGame
from .stations import (BSInstruction, CSInstruction, DSInstruction, RSInstruction,
                       StationConfig)
from .timing import Timing, parse_phase_lengths
from .world import RefboxWorld, SlotEvent, TableWorld, Workpiece

__all__ = ["RefboxGame", "Event", "ReportEntry", "BSInstruction", "CSInstruction",
           "DSInstruction", "RSInstruction", "StationConfig", "Timing", "parse_phase_lengths",
           "RefboxWorld", "SlotEvent", "TableWorld", "Workpiece"]
