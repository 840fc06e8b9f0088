"""Camera intrinsics from a calibration file.

Two layouts are read, both YAML:

* OpenCV's FileStorage (``%YAML:1.0``, ``!!opencv-matrix``), as
  ``cv2.calibrateCamera`` tools write it: ``camera_matrix``,
  ``distortion_coefficients``, ``image_width``, ``image_height``;
* ROS ``camera_calibration``'s plain YAML: the same keys, the matrices as
  ``{rows, cols, data}``.

:func:`load_intrinsics` returns :class:`rll_bt.backend.CameraIntrinsics`;
:func:`scaled` fits them to a frame of another size (a camera run at a
lower resolution than it was calibrated at).  Bad files raise
:class:`CalibrationError` naming the file and the key.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from rll_bt.backend import CameraIntrinsics


class CalibrationError(ValueError):
    pass


def _matrix(node, where: str) -> np.ndarray:
    if isinstance(node, dict) and "data" in node:
        data = np.asarray(node["data"], dtype=float)
        rows, cols = int(node.get("rows", 1)), int(node.get("cols", data.size))
        if data.size != rows * cols:
            raise CalibrationError(f"{where}: {data.size} values for a {rows}x{cols} matrix")
        return data.reshape(rows, cols)
    return np.asarray(node, dtype=float)


def _from_filestorage(path: Path) -> dict:
    import cv2
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        if not fs.isOpened():
            raise CalibrationError(f"{path}: not an OpenCV FileStorage file")
        out = {}
        for key in ("camera_matrix", "distortion_coefficients"):
            node = fs.getNode(key)
            if not node.empty():
                out[key] = node.mat() if node.isMap() else np.asarray([node.at(i).real() for i in range(node.size())])
        for key in ("image_width", "image_height"):
            node = fs.getNode(key)
            if not node.empty():
                out[key] = int(node.real())
        return out
    finally:
        fs.release()


def load_intrinsics(path: str | Path) -> CameraIntrinsics:
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise CalibrationError(f"{path}: cannot read: {exc.strerror}") from None
    if text.lstrip().startswith("%YAML"):
        try:
            data = _from_filestorage(path)
        except Exception as exc:          # OpenCV's parser errors are cv2.error
            if isinstance(exc, CalibrationError):
                raise
            raise CalibrationError(f"{path}: {exc}") from None
    else:
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise CalibrationError(f"{path}: not YAML: {exc}") from None
        if not isinstance(data, dict):
            raise CalibrationError(f"{path}: expected a mapping with camera_matrix")
    for key in ("camera_matrix", "image_width", "image_height"):
        if key not in data or data[key] is None:
            raise CalibrationError(f"{path}: no {key}")
    k = _matrix(data["camera_matrix"], f"{path}: camera_matrix")
    if k.shape != (3, 3) or not np.all(np.isfinite(k)) or k[0, 0] <= 0 or k[1, 1] <= 0:
        raise CalibrationError(f"{path}: camera_matrix must be a 3x3 matrix with positive focal lengths")
    dist = data.get("distortion_coefficients")
    d = _matrix(dist, f"{path}: distortion_coefficients").ravel() if dist is not None else np.zeros(5)
    w, h = int(data["image_width"]), int(data["image_height"])
    if w <= 0 or h <= 0:
        raise CalibrationError(f"{path}: image size {w}x{h}")
    return CameraIntrinsics(w, h, float(k[0, 0]), float(k[1, 1]), float(k[0, 2]), float(k[1, 2]),
                            tuple(float(v) for v in d))


def scaled(intr: CameraIntrinsics, width: int, height: int) -> CameraIntrinsics:
    """``intr`` for frames of ``width`` x ``height``."""
    if (width, height) == (intr.width, intr.height):
        return intr
    sx, sy = width / intr.width, height / intr.height
    return CameraIntrinsics(width, height, intr.fx * sx, intr.fy * sy, intr.cx * sx, intr.cy * sy, intr.distortion)


def write_filestorage(path: str | Path, intr: CameraIntrinsics) -> None:
    """Write ``intr`` as OpenCV's calibration tools do (used by the emulators)."""
    import cv2
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", intr.width)
    fs.write("image_height", intr.height)
    fs.write("camera_matrix", intr.matrix)
    fs.write("distortion_coefficients", np.asarray(intr.distortion, dtype=float).reshape(1, -1))
    fs.release()
