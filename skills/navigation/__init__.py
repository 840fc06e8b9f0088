"""Navigation: costmap, global planner, path follower, laser safety, goals,
and the :class:`Navigate` activity."""
from .controller import Limits, PathFollower, VelocityLimiter, heading_command
from .costmap import Costmap
from .goals import PoseGoal, StationSideGoal, ZoneGoal, approach_pose, side_sign, target_lateral
from .navigate import Navigate
from .planner import GridPlanner, NoPath, shortcut
from .safety import clear_distance, scan_points, speed_limit, to_field

__all__ = ["Limits", "PathFollower", "VelocityLimiter", "heading_command", "Costmap", "PoseGoal",
           "StationSideGoal", "ZoneGoal", "approach_pose", "side_sign", "target_lateral", "Navigate",
           "GridPlanner", "NoPath", "shortcut", "clear_distance", "scan_points", "speed_limit", "to_field"]
