"""Festo Robotino 3 over its USB serial link ("direct" protocol), with the
Carologistics RCLL gripper on an Arduino, plus a firmware-faithful emulator.

Modules: ``framing`` (frames, checksum, stuffing, streaming decoder),
``tags`` (every tag as a typed value), ``kinematics`` and ``ramp``,
``base`` (the polling driver), ``gripper_protocol`` and ``gripper``,
``config`` (the robot configuration file) and ``parts`` (its laser and
camera), ``backend`` (:class:`RobotinoBackend`), ``firmware``/``arduino``/
``faults``/``emulator`` (the emulator), ``cli``.

The ``robotino`` entry point is :func:`open_robotino`: a Robotino 3, or the
Robotino 4 REST backend when the robot configuration says ``base: {type:
robotino4}``.
"""
from .backend import RobotinoBackend


def open_robotino(device: str | None = None, *, robot_config=None, clock=None, **options):
    """``open_backend("robotino", ...)``: see :mod:`.backend`; a robot
    configuration whose base is a Robotino 4 opens the REST backend with the
    same laser, camera and gripper."""
    if robot_config is not None:
        from .config import as_config
        cfg = as_config(robot_config)
        if cfg.base["type"] == "robotino4":
            from backends.robotino_rest import RobotinoRestBackend
            return RobotinoRestBackend(robot_config=cfg, clock=clock, **options)
        robot_config = cfg
    return RobotinoBackend(device, robot_config=robot_config, clock=clock, **options)


__all__ = ["RobotinoBackend", "open_robotino"]
