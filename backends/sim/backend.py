"""``SimBackend``: one simulated robot behind :class:`rll_bt.backend.Backend`.

    world = World("rcll2016", seed=3)
    robot = open_backend("sim", world=world, robot=("CYAN", 1))
    robot.drive(0.3, 0.0, 0.0)
    world.step(1.0)
    robot.odometry().pose

Options of ``open_backend("sim", ...)`` / ``SimBackend(...)``:

- ``world``: the :class:`~backends.sim.world.World` (required);
- ``robot``: ``(team, number)``, or a number for a cyan robot (default 1);
- ``pose``: start pose when the robot is not in the world yet (default: its
  insertion lane);
- any :class:`~backends.sim.robot.RobotConfig` field (``deadman``,
  ``odom_frame``, ``laser_noise``, ``grab_failure``, ``camera_width``, ...),
  applied when the backend adds the robot to the world (a robot already in
  the world keeps its configuration; passing options then is an error).

The backend never advances time: whoever owns the world calls
``world.step``.  Readings are those of the current sim time; ground truth is
read from the world (``world.robot_pose(team, n)``), never from here.

Perception: with ``world.perception == "oracle"`` :meth:`detections` reports
the tags and lights in view (capability ``DETECTIONS``); with ``"rendered"``
it raises :class:`CapabilityError` and skills run their detectors on
:meth:`camera_image`.  Gripper: see :mod:`backends.sim.gripper` for the axes;
:meth:`gripper_status` ``holding`` is the truth, and ``sensed`` whether a workpiece is
between the fingers (one held, or one a close would take).
"""
from __future__ import annotations

from rll_bt.backend import (
    Backend,
    Battery,
    CameraImage,
    Capability,
    CapabilityError,
    Detections,
    GripperStatus,
    LaserScan,
    Odometry,
)
from rll_bt.rules import CYAN

from .world import World


class SimBackend(Backend):
    name = "sim"

    def __init__(self, world: World, robot: tuple[str, int] | int = 1, pose=None, **options):
        if not isinstance(world, World):
            raise TypeError(f"the sim backend needs world=World(...), got {type(world).__name__}")
        team, number = (CYAN, robot) if isinstance(robot, int) else robot
        self.world = world
        key = (str(team).upper(), int(number))
        if key in world.robots:
            if options or pose is not None:
                raise ValueError(f"robot {key[0]}/{key[1]} is already in the world; "
                                 "options apply only when the backend adds it")
            self._robot = world.robots[key]
        else:
            self._robot = world.add_robot(key[0], key[1], pose=pose, **options)
        self._closed = False

    @property
    def robot(self):
        """The world's state of this robot (tests only: ground truth lives here)."""
        return self._robot

    @property
    def capabilities(self) -> Capability:
        caps = (Capability.DRIVE | Capability.ODOMETRY | Capability.LASER | Capability.CAMERA
                | Capability.GRIPPER | Capability.BUMPER | Capability.BATTERY)
        if self.world.perception == "oracle":
            caps |= Capability.DETECTIONS
        return caps

    # -- motion -------------------------------------------------------------
    def drive(self, vx: float, vy: float, omega: float) -> None:
        self._robot.drive(vx, vy, omega, self.world.time)

    def stop(self) -> None:
        self._robot.stop(self.world.time)

    def odometry(self) -> Odometry:
        r = self._robot
        vx, vy, w = r.velocity
        return Odometry(self.world.time, r.odom, vx, vy, w)

    # -- sensors ------------------------------------------------------------
    def laser_scan(self) -> LaserScan:
        return self.world.laser_scan(self._robot)

    def camera_image(self, camera: str = "front") -> CameraImage:
        if camera != "front":
            raise CapabilityError(f"sim: no camera {camera!r} (only 'front')")
        return self.world.camera_image(self._robot, camera)

    def detections(self, camera: str = "front") -> Detections:
        if self.world.perception != "oracle":
            raise CapabilityError("sim: perception is 'rendered'; run the detectors on camera_image()")
        if camera != "front":
            raise CapabilityError(f"sim: no camera {camera!r} (only 'front')")
        return self.world.detections(self._robot, camera)

    def bumper(self) -> bool:
        return self.world.bumper(self._robot)

    def battery(self) -> Battery:
        return self._robot.battery(self.world.time)

    # -- gripper ------------------------------------------------------------
    def gripper_open(self) -> None:
        self._robot.gripper.command("open", now=self.world.time)

    def gripper_close(self) -> None:
        self._robot.gripper.command("close", now=self.world.time)

    def gripper_move(self, x: float, y: float, z: float) -> None:
        self._robot.gripper.command("move", (x, y, z), now=self.world.time)

    def gripper_status(self) -> GripperStatus:
        g = self._robot.gripper
        held = self._robot.holding is not None
        return GripperStatus(g.state(), g.is_open, tuple(g.position), holding=held,
                             sensed=held or self.world.within_grip(self._robot) is not None)

    def close(self) -> None:
        if not self._closed and self.world.connected:
            self.stop()
        self._closed = True

