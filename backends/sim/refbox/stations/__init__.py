"""Station state machines of the production phase, one module per station type.

:mod:`.base` holds what every station shares (timed steps, breaking,
down periods; :class:`~.base.Station`), :mod:`.lights` the states and their
signal-tower lights; :mod:`.bs`, :mod:`.rs`,
:mod:`.cs`, :mod:`.ds` and :mod:`.ss` (the 2017+ storage station) add what
their type does with a workpiece.  :func:`make_station` builds the station
for a machine name.
"""
from __future__ import annotations

from .base import BUSY_STATES, Station, StationConfig, StationHost
from .bs import BaseStation, BSInstruction
from .cs import CapStation, CSInstruction
from .ds import DeliveryStation, DSInstruction
from .lights import (
    BROKEN,
    DOWN,
    IDLE,
    PREPARED,
    PROCESSED,
    PROCESSING,
    READY_AT_OUTPUT,
    STATE_LIGHTS,
    STATE_LIGHTS_2025,
    STATES,
    WAIT_IDLE,
)
from .rs import RingStation, RSInstruction
from .ss import SSInstruction, StorageStation

KINDS = {"BS": BaseStation, "RS": RingStation, "CS": CapStation, "DS": DeliveryStation,
         "SS": StorageStation}


def make_station(name: str, team: str, host: StationHost) -> Station:
    """The station model for machine ``name`` ("C-RS1" -> a :class:`RingStation`)."""
    try:
        cls = KINDS[name[2:4]]
    except KeyError:
        raise ValueError(f"no station model for {name!r}") from None
    return cls(name=name, team=team, host=host)


__all__ = ["Station", "StationConfig", "StationHost", "make_station", "KINDS",
           "BaseStation", "RingStation", "CapStation", "DeliveryStation", "StorageStation",
           "BSInstruction", "RSInstruction", "CSInstruction", "DSInstruction", "SSInstruction",
           "IDLE", "PREPARED", "PROCESSING", "PROCESSED", "READY_AT_OUTPUT", "WAIT_IDLE",
           "BROKEN", "DOWN", "STATES", "BUSY_STATES", "STATE_LIGHTS", "STATE_LIGHTS_2025"]
