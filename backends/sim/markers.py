"""ArUco marker textures (``cv2.aruco.DICT_ARUCO_ORIGINAL``) for the station
tags, and the textured quad that carries one on a station face.

The texture is the 7 x 7 cell marker with a one-cell white margin, so the
quad is ``tag_size * 9 / 7`` wide where ``tag_size`` is the black square's
width (the profile's printed marker size).  TinyRenderer samples textures
with v pointing up, so the quad's UVs are set to keep the rendered marker
un-mirrored: a camera image decodes to the right id.
"""
from __future__ import annotations

import os
import tempfile

import cv2
import numpy as np

CELLS = 7          # 5 x 5 bits plus the black border
MARGIN_CELLS = 1   # white quiet zone on each side
CELL_PX = 16


def dictionary():
    return cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_ARUCO_ORIGINAL)


def quad_size(tag_size: float) -> float:
    """Edge of the white quad carrying a marker whose black square is ``tag_size``."""
    return tag_size * (CELLS + 2 * MARGIN_CELLS) / CELLS


def marker_image(tag_id: int) -> np.ndarray:
    """Grey image of the marker with its white margin (uint8)."""
    n = dictionary().bytesList.shape[0]
    if not 0 <= tag_id < n:
        raise ValueError(f"tag id {tag_id} is outside DICT_ARUCO_ORIGINAL (0..{n - 1})")
    side = CELLS * CELL_PX
    pad = MARGIN_CELLS * CELL_PX
    img = np.full((side + 2 * pad, side + 2 * pad), 255, np.uint8)
    img[pad:pad + side, pad:pad + side] = cv2.aruco.generateImageMarker(dictionary(), tag_id, side)
    return img


def texture_file(tag_id: int, directory: str | None = None) -> str:
    """Path of a PNG of the marker, written once into a cache directory."""
    directory = directory or os.path.join(tempfile.gettempdir(), "rll_bt_sim_markers")
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"aruco_original_{tag_id}.png")
    if not os.path.exists(path):
        fd, tmp = tempfile.mkstemp(suffix=".png", dir=directory)
        os.close(fd)
        if not cv2.imwrite(tmp, marker_image(tag_id)):
            os.unlink(tmp)
            raise OSError(f"cannot write marker texture {tmp}")
        os.replace(tmp, path)   # atomic: parallel workers may race here
    return path


def quad_mesh(half: float) -> dict:
    """Mesh arguments of a square quad in its own frame: the marker face
    looks along +z, the marker's "up" is +y, its "right" is +x (the OpenCV
    marker frame)."""
    tl, tr, br, bl = (-half, half, 0.0), (half, half, 0.0), (half, -half, 0.0), (-half, -half, 0.0)
    return {
        "vertices": [tl, tr, br, bl],
        "indices": [0, 2, 1, 0, 3, 2],
        "uvs": [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)],
        "normals": [(0.0, 0.0, 1.0)] * 4,
    }
