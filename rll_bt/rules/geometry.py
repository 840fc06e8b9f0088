"""Station (MPS), workpiece and robot geometry shared by the simulation and
the perception skills.  Facts: field-vision-sim.md §2-§3.

Machine frame: the MPS local x axis runs along the conveyor from the output
side to the input side (rulebook convention), y to the left of it, z up, the
origin at the centre of the footprint on the floor.  The footprint is
0.35 m along x (the conveyor's length) by 0.7 m along y; the input face is at
x = +0.175 and the output face at x = -0.175.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MpsGeometry:
    depth: float = 0.35                 # along the conveyor (machine x)
    width: float = 0.70                 # across (machine y)
    height: float = 0.95                # cabinet top
    belt_height: float = 0.898          # conveyor, shelf and slide working height
    belt_offset_y: float = 0.025        # conveyor centre line from the machine centre
    belt_width: float = 0.045 * 2       # guide lane gap is 4.5 cm; the belt is a bit wider
    # the signal tower stands on the cabinet near the output lane
    tower_x: float = -0.10
    tower_y: float = -0.22
    tower_base: float = 0.95
    tower_radius: float = 0.018         # Festo #549843: diameter 36 mm
    tower_segment: float = 0.034        # per light including a 5 mm unlit border
    tower_segment_border: float = 0.005
    tower_cap: float = 0.045            # housing above the three segments (147 mm total)
    # fiducial: one per side, horizontally centred below the belt
    tag_centre_height: float = 0.48     # upper edge about 35 cm below the belt
    # cap station shelf and ring station slide sit on the input side, beside the belt, on the
    # right of a robot facing the input (machine +y): the side the real refbox's fixed rotations
    # of an RS/CS twin by a wall keep off the wall (refbox-protocol.md, mirroring)
    # (slot 0 farthest from the belt; 0.295, 0.215 and 0.135 m from its centre line, the slide 0.225)
    shelf_y: tuple[float, float, float] = (0.32, 0.24, 0.16)
    slide_y: float = 0.25

    @property
    def tower_height(self) -> float:
        return 3 * self.tower_segment + self.tower_cap

    def segment_centre_z(self, index: int) -> float:
        """Height of light ``index`` (0 = green at the bottom, 1 = yellow, 2 = red)."""
        return self.tower_base + self.tower_segment * (index + 0.5)


@dataclass(frozen=True)
class RobotGeometry:
    radius: float = 0.225               # Robotino 3: diameter 450 mm
    height: float = 0.29
    max_speed: float = 0.7              # m/s, rules limit
    max_omega: float = 1.6              # rad/s
    max_accel: float = 0.8              # m/s^2 (host ramp default)
    max_decel: float = 1.5
    max_alpha: float = 1.6              # rad/s^2
    laser_mount: tuple[float, float, float] = (0.17, 0.0, 0.22)   # x, y, z in the robot frame
    laser_fov: float = 4.18879          # 240 degrees
    laser_beams: int = 240
    laser_range: tuple[float, float] = (0.03, 10.0)
    camera_mount: tuple[float, float, float] = (0.20, 0.0, 0.57)
    camera_hfov: float = 1.08           # rad (gazebo tag-vision value)
    camera_range: float = 6.0
    gripper_reach: float = 0.25         # from the robot centre to the gripped workpiece centre


@dataclass(frozen=True)
class WorkpieceGeometry:
    radius: float = 0.02
    base_height: float = 0.0225
    ring_height: float = 0.008
    cap_height: float = 0.004


MPS = MpsGeometry()
ROBOT = RobotGeometry()
WORKPIECE = WorkpieceGeometry()
