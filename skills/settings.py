"""Limits and tolerances of the skills, in one place (SI units: metres,
seconds, radians).  ``SkillContext.settings`` holds a :class:`SkillSettings`;
its ``manipulation`` field the station-handling values."""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class ManipulationSettings:
    """Station approach and gripper use.

    Distances are from the robot centre to the station face.  The camera
    cannot see the tag closer than about 0.55 m (it sits 35 cm below the
    belt, the camera at 0.57 m), so the robot lines up with the tag at
    ``coarse_distance`` and covers the rest by laser (``final_distance``).
    """
    coarse_distance: float = 0.62
    tag_min_distance: float = 0.57   # closer, the camera no longer sees the whole tag
    final_distance: float = 0.27      # 4.5 cm between the robot and the face
    slot_inset: float = 0.03          # a slot's centre lies this far inside the face
    # the gripper's sideways axis (the sim's and the Carologistics gantry's: +-0.10 m) lets a
    # robot that has no room squarely in front of a shelf slot stand up to this far beside it
    # (toward the belt) and reach over; it keeps ``side_margin`` from the wall or station there
    # (the motion guard stops a sideways move 3 cm short of what the laser sees, and the pose
    # is a centimetre or two off: with 2 cm, 2016 seed 11's moves to C-CS1's slot 0 stopped short)
    side_reach: float = 0.09
    # the gripper's sideways axis (+-0.10 m): a docked sideways move to a spot that a wall or
    # station stops a little short (the guard's band) is made up by the gripper up to this
    side_axis: float = 0.10
    side_margin: float = 0.05
    align_tolerance: float = 0.008    # m, lateral and along the tag normal
    align_heading_tolerance: float = 0.015   # rad
    align_speed: float = 0.15         # m/s
    align_settle: float = 0.3         # s inside the tolerance before success
    tag_sightings: int = 5            # sightings needed before trusting the tag
    tag_search_time: float = 3.0      # s without the tag before ALIGN_FAILED
    align_time: float = 20.0          # s to line up before ALIGN_FAILED
    dock_speed: float = 0.1           # m/s on the final approach
    dock_tolerance: float = 0.005     # m
    dock_time: float = 15.0           # s
    back_off: float = 0.35            # m driven backwards after a grab or put
    gripper_step_time: float = 10.0   # s for one gripper action before GRIPPER_ERROR


@dataclass
class SkillSettings:
    max_speed: float = 0.7            # m/s, the rules' limit
    max_omega: float = 1.6            # rad/s
    max_accel: float = 0.8            # m/s^2
    max_decel: float = 1.2            # m/s^2, planned; the base can do 1.5
    emergency_decel: float = 1.5      # m/s^2, braking for an obstacle the laser sees
    max_alpha: float = 1.6            # rad/s^2
    control_period: float = 0.1       # s, the expected time between polls
    position_tolerance: float = 0.05  # m, a navigation goal is reached
    heading_tolerance: float = 0.05   # rad
    safety_margin: float = 0.08       # m, kept free around the robot by the laser check
    blind_speed: float = 0.2          # m/s, top speed toward where the laser cannot see
    closing_speed: float = 0.5        # m/s an unmapped obstacle (another robot) may approach at
    plan_padding: float = 0.08        # m, added to the robot radius in the costmap
    obstacle_padding: float = 0.08    # m, more for laser obstacles (robots): the laser check's wider berth
    tight_min_speed: float = 0.25     # m/s passing a wall or station at the plan padding
    tight_slope: float = 4.0          # m/s more per metre of gap beyond the padding
    costmap_resolution: float = 0.05  # m
    obstacle_ttl: float = 4.0         # s, laser obstacles stay in the costmap
    block_replan_after: float = 1.0   # s blocked before replanning around it
    # giving way to another robot (navigation.yielding): after yield_after + yield_step * (rank - 1, and
    # a quarter step for the tie-break) seconds blocked by it with no way round, step aside for yield_hold
    yield_after: float = 1.5          # s
    yield_step: float = 5.5           # s per rank above 1 (the robot's number)
    yield_hold: float = 6.0           # s standing aside before the robot tries its way again
    max_yields: int = 2               # per navigation
    manipulation: ManipulationSettings = field(default_factory=ManipulationSettings)
