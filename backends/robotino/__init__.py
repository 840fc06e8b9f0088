"""Festo Robotino 3 over its USB serial link ("direct" protocol), with the
Carologistics RCLL gripper on an Arduino, plus a firmware-faithful emulator.

Modules: ``framing`` (frames, checksum, stuffing, streaming decoder),
``tags`` (every tag as a typed value), ``kinematics`` and ``ramp``,
``base`` (the polling driver), ``gripper_protocol`` and ``gripper``,
``backend`` (:class:`RobotinoBackend`, entry point ``robotino``),
``firmware``/``arduino``/``faults``/``emulator`` (the emulator), ``cli``.
"""
from .backend import RobotinoBackend

__all__ = ["RobotinoBackend"]
