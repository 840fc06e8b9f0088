"""Test doubles for developing and testing skills without physics.

:class:`FlatWorld` is a 2D kinematic world implementing the backend
interface per robot (:class:`FlatRobot`): exact ray-cast laser, noisy
odometry, collisions counted, oracle tag detections and a simple gripper.
It is a stand-in for unit tests and benchmarks, not a simulator of record
(that is ``backends/sim``).
"""
from .flatworld import FlatRobot, FlatWorld, Station, Workpiece

__all__ = ["FlatWorld", "FlatRobot", "Station", "Workpiece"]
