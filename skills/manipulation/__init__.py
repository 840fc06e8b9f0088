"""Station handling: places on a station, tag alignment, laser docking,
gripper sequences with the holding check, and grab / put activities."""
from .align import AlignToTag, Dock, fit_face
from .gripper import GripperSequence
from .places import Place, check_place, gripper_height, gripper_target, lateral_offset, place_for
from .station import ApproachStation, GrabFrom, PutOnto, gripper_home, tags_available
from .tagview import tag_pose_in_robot

__all__ = ["AlignToTag", "Dock", "fit_face", "GripperSequence", "Place", "check_place", "gripper_height",
           "gripper_target", "lateral_offset", "place_for", "ApproachStation", "GrabFrom", "PutOnto",
           "gripper_home", "tags_available", "tag_pose_in_robot"]
