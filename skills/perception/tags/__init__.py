"""Machines from fiducial tags: ArUco detection, pose by solvePnP, the
field pose of the tag's machine, and a Kalman filter per machine.

    detector = TagDetector(profile.tag_size, valid_ids=profile.all_tag_ids)
    tracker = MachineTracker(profile)
    for det in detector.detect(img.image, img.intrinsics):
        tracker.add(det, img.extrinsics, robot_pose)
    tracker.estimate("C-BS")   # pose, zone, rotation_deg, confidence
"""
from .detector import DICTIONARY, TagDetector, marker_object_points
from .geometry import TagInField, machine_pose_from_tag, tag_in_field, tag_in_robot, tag_pose_on_machine
from .tracker import MachineEstimate, MachineTracker

__all__ = ["DICTIONARY", "TagDetector", "marker_object_points", "TagInField", "machine_pose_from_tag",
           "tag_in_field", "tag_in_robot", "tag_pose_on_machine", "MachineEstimate", "MachineTracker"]
