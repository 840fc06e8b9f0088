"""The remote backend's values as JSON and back.

Results are plain JSON: laser ranges and camera images as base64 of
little-endian float32 / uint8 arrays, poses as [x, y, theta], stamps in the
server's seconds (:func:`decode` moves them onto the client's clock).
"""
from __future__ import annotations

import base64

import numpy as np

from rll_bt.backend import (
    BackendError,
    BackendUnavailable,
    Battery,
    CameraExtrinsics,
    CameraImage,
    CameraIntrinsics,
    Capability,
    CapabilityError,
    Detections,
    GripperState,
    GripperStatus,
    LaserScan,
    LightDetection,
    Odometry,
    Pose2D,
    TagDetection,
)

#: the backend methods a client may call
METHODS = ("capabilities", "drive", "stop", "odometry", "laser_scan", "camera_image", "detections",
           "bumper", "battery", "gripper_open", "gripper_close", "gripper_move", "gripper_status")
#: errors that cross the link as themselves (anything else arrives as BackendError)
ERRORS = {"CapabilityError": CapabilityError, "BackendUnavailable": BackendUnavailable,
          "BackendError": BackendError}


def _b64(arr: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(arr).tobytes()).decode("ascii")


def _pose(p: Pose2D) -> list[float]:
    return [p.x, p.y, p.theta]


# -- values to JSON and back ----------------------------------------------------------------------
def encode(value):
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, Capability):
        return int(value.value)
    if isinstance(value, Odometry):
        return {"stamp": value.stamp, "pose": _pose(value.pose), "v": [value.vx, value.vy, value.omega]}
    if isinstance(value, LaserScan):
        return {"stamp": value.stamp, "angle_min": value.angle_min, "angle_increment": value.angle_increment,
                "range_min": value.range_min, "range_max": value.range_max,
                "ranges": _b64(np.asarray(value.ranges, dtype="<f4")), "mount": _pose(value.mount)}
    if isinstance(value, Detections):
        return {"stamp": value.stamp, "extrinsics": _extr(value.extrinsics),
                "tags": [{"tag_id": t.tag_id, "tvec": list(t.tvec), "rvec": list(t.rvec),
                          "corners": [list(c) for c in t.corners], "camera": t.camera} for t in value.tags],
                "lights": [{"box": list(lt.box), "state": lt.state, "score": lt.score,
                            "probabilities": list(lt.probabilities), "camera": lt.camera, "tag_id": lt.tag_id}
                           for lt in value.lights]}
    if isinstance(value, GripperStatus):
        return {"state": value.state.value, "is_open": value.is_open, "position": list(value.position),
                "holding": value.holding, "message": value.message, "sensed": value.sensed}
    if isinstance(value, Battery):
        return {"voltage": value.voltage, "current": value.current, "soc": value.soc,
                "external_power": value.external_power}
    if isinstance(value, CameraImage):
        i = value.intrinsics
        return {"stamp": value.stamp, "shape": list(value.image.shape), "data": _b64(value.image.astype(np.uint8)),
                "intrinsics": [i.width, i.height, i.fx, i.fy, i.cx, i.cy, list(i.distortion)],
                "extrinsics": _extr(value.extrinsics), "camera": value.camera}
    raise TypeError(f"cannot send a {type(value).__name__} over the remote backend")


def _extr(e: CameraExtrinsics) -> dict:
    return {"position": list(e.position), "yaw": e.yaw, "pitch": e.pitch}


def _unextr(d: dict) -> CameraExtrinsics:
    return CameraExtrinsics(tuple(d["position"]), d["yaw"], d["pitch"])


def decode(method: str, r, shift: float = 0.0):
    """A result of ``method`` back into the backend's types; stamps + ``shift``."""
    if r is None or method not in ("capabilities", "odometry", "laser_scan", "detections", "gripper_status",
                                   "battery", "camera_image"):
        return r
    if method == "capabilities":
        return Capability(r)
    if method == "odometry":
        return Odometry(r["stamp"] + shift, Pose2D(*r["pose"]), *r["v"])
    if method == "laser_scan":
        ranges = np.frombuffer(base64.b64decode(r["ranges"]), dtype="<f4").astype(np.float64)
        return LaserScan(r["stamp"] + shift, r["angle_min"], r["angle_increment"], r["range_min"],
                         r["range_max"], ranges, Pose2D(*r["mount"]))
    if method == "detections":
        tags = tuple(TagDetection(t["tag_id"], tuple(t["tvec"]), tuple(t["rvec"]),
                                  tuple(tuple(c) for c in t["corners"]), t["camera"]) for t in r["tags"])
        lights = tuple(LightDetection(tuple(lt["box"]), lt["state"], lt["score"], tuple(lt["probabilities"]),
                                      lt["camera"], lt["tag_id"]) for lt in r["lights"])
        return Detections(r["stamp"] + shift, tags, lights, _unextr(r["extrinsics"]))
    if method == "gripper_status":
        return GripperStatus(GripperState(r["state"]), r["is_open"], tuple(r["position"]), r["holding"],
                             r["message"], r.get("sensed"))
    if method == "battery":
        return Battery(**r)
    w, h, fx, fy, cx, cy, dist = r["intrinsics"]
    img = np.frombuffer(base64.b64decode(r["data"]), dtype=np.uint8).reshape(r["shape"])
    return CameraImage(r["stamp"] + shift, img.copy(), CameraIntrinsics(w, h, fx, fy, cx, cy, tuple(dist)),
                       _unextr(r["extrinsics"]), r["camera"])
