"""The PyBullet world's game against a refbox elsewhere: the real refbox (or
``rll-bt refbox sim`` in its network mode) drives the world's stations over
MQTT or OPC-UA and follows the world's clock (SimTimeSync), while the team
server and the agents talk to it on its own ports (``rll-bt sim --refbox
external``).

- :mod:`.link`: the refbox's controller stream: the operator's commands out,
  the game as every controller hears it in (:class:`ControllerLink`);
- :mod:`.refbox`: the world built on the refbox's field, its stations served,
  its time sent (:func:`open_external`, :class:`ExternalRefbox`).
"""
from .link import ControllerLink
from .refbox import CONTROLS, STATIONS, ExternalRefbox, HeldHall, open_external

__all__ = ["CONTROLS", "STATIONS", "ControllerLink", "ExternalRefbox", "HeldHall", "open_external"]
