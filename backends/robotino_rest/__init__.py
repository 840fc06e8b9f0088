"""Festo Robotino 4 over the robot's HTTP REST API (``restapid``, port 80):
omnidrive, odometry, bumper, IR distance sensors, laser scan and camera.
:class:`RobotinoRestBackend` is the ``robotino_rest`` backend;
:class:`standin.RestStandIn` is a local fake of the API for tests and demos.
"""
from .backend import RobotinoRestBackend

__all__ = ["RobotinoRestBackend"]
