"""The world's stations served as machines a real referee box drives.

The real refbox drives Festo MPS stations over OPC-UA (the PLC's
registers) or over MQTT topics (``reference/refbox-mqtt.md``).  This
package runs each station of a PyBullet :class:`~backends.sim.world.World`
as such a machine, through the world's station API only:

- :class:`MpsMachine` (:mod:`.machine`): one station on the world's clock,
  commands in, feedback (busy, workpiece sensor, slide counter, barcode)
  out, the Festo durations (:class:`Durations`);
- :class:`MachineHall` (:mod:`.hall`): every station, a thread-safe inbox
  for the network front ends, :meth:`MachineHall.update` after each world
  step;
- :class:`MqttMachines` (:mod:`.mqtt`) on a broker (:class:`Broker`,
  :mod:`.broker`: amqtt or mosquitto), and :class:`OpcuaMachines`
  (:mod:`.opcua`), one OPC-UA server per station with the Festo PLC's node
  layout;
- :mod:`.commands`: the commands of both wires.

Quick start (a world whose stations a refbox configured with
``connection: mqtt`` drives)::

    from backends.sim import World
    from backends.sim.mps import Broker, MachineHall, MqttMachines
    world = World("rcll2025", seed=1)
    hall = MachineHall(world)
    with Broker() as broker, MqttMachines(hall, broker.host, broker.port):
        while True:
            world.step(0.02)
            hall.update()            # on the world's thread, after each step
"""
from __future__ import annotations

import importlib

_EXPORTS = {
    "Command": "commands", "CommandError": "commands", "parse_mqtt": "commands",
    "from_opcua": "commands",
    "MpsMachine": "machine", "Durations": "machine", "Feedback": "machine", "Product": "machine",
    "MachineHall": "hall", "DEFAULT_STORAGE": "hall",
    "MqttMachines": "mqtt",
    "OpcuaMachines": "opcua",
    "Broker": "broker", "BrokerError": "broker",
}

__all__ = [
    "DEFAULT_STORAGE",
    "Broker",
    "BrokerError",
    "Command",
    "CommandError",
    "Durations",
    "Feedback",
    "MachineHall",
    "MpsMachine",
    "MqttMachines",
    "OpcuaMachines",
    "Product",
    "from_opcua",
    "parse_mqtt",
]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
