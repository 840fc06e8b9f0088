"""ArUco detection and tag pose by solvePnP.

Markers are from ``cv2.aruco.DICT_ARUCO_ORIGINAL`` (the rulebook's "original
ARUCO dictionary, 5x5 bits").  The pose of each marker is returned in the
camera optical frame (z forward, x right, y down) in OpenCV's convention:
the tag frame has x to the marker's right, y up and z out of the marker face
towards the viewer, origin at the marker centre.
"""
from __future__ import annotations

import cv2
import numpy as np

from rll_bt.backend import CameraIntrinsics, TagDetection

DICTIONARY = cv2.aruco.DICT_ARUCO_ORIGINAL


def marker_object_points(size: float) -> np.ndarray:
    """Corners (top-left, top-right, bottom-right, bottom-left) in the tag frame,
    the order ArUco reports image corners in and IPPE_SQUARE expects."""
    h = size / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]], dtype=np.float64)


class TagDetector:
    """Finds markers in a BGR or grey image and estimates their poses.

    ``valid_ids`` (optional) drops every id outside the set, so decoding noise
    on background texture never yields a station.
    """

    def __init__(self, tag_size: float, valid_ids: set[int] | None = None,
                 min_side_px: float = 12.0):
        self.tag_size = float(tag_size)
        self.valid_ids = set(valid_ids) if valid_ids is not None else None
        self.min_side_px = min_side_px
        params = cv2.aruco.DetectorParameters()
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
        # a tag whose white margin reaches the image's edge is still whole: with
        # OpenCV's default (3 px) the tag was lost in a band where its margin ends
        # 1-3 px above the bottom edge, 0.60-0.615 m from the face in the sim's
        # camera, right where the robot lines up with a station (coarse_distance)
        params.minDistanceToBorder = 0
        self._detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(DICTIONARY), params)
        self._obj = marker_object_points(self.tag_size)

    def detect_corners(self, image: np.ndarray) -> list[tuple[int, np.ndarray]]:
        """(id, 4x2 corner array) of every marker found."""
        grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        corners, ids, _ = self._detector.detectMarkers(grey)
        out = []
        if ids is None:
            return out
        for c, i in zip(corners, ids.ravel()):
            tag_id = int(i)
            if self.valid_ids is not None and tag_id not in self.valid_ids:
                continue
            pts = c.reshape(4, 2).astype(np.float64)
            if min(np.linalg.norm(pts - np.roll(pts, 1, axis=0), axis=1)) < self.min_side_px:
                continue
            out.append((tag_id, pts))
        return out

    def detect(self, image: np.ndarray, intrinsics: CameraIntrinsics, camera: str = "front",
               up: np.ndarray | None = None) -> list[TagDetection]:
        """Markers with their pose in the camera optical frame.

        A small square seen from afar has two nearly equally good poses
        (mirrored about the line of sight).  ``up`` (the world's up direction
        in the optical frame, e.g. ``extrinsics.rotation().T @ (0, 0, 1)``)
        resolves it for markers mounted upright: the pose whose marker y axis
        points most nearly up wins, unless its reprojection error is clearly
        worse.
        """
        k = intrinsics.matrix
        dist = np.asarray(intrinsics.distortion, dtype=np.float64)
        found = []
        for tag_id, pts in self.detect_corners(image):
            pose = self._solve(pts, k, dist, up)
            if pose is None:
                continue
            rvec, tvec = pose
            found.append(TagDetection(tag_id=tag_id, tvec=tuple(float(v) for v in tvec.ravel()),
                                      rvec=tuple(float(v) for v in rvec.ravel()),
                                      corners=tuple((float(x), float(y)) for x, y in pts),
                                      camera=camera))
        return found

    def _solve(self, pts, k, dist, up):
        # IPPE_SQUARE returns NaN for a tag seen squarely, its corners an exact
        # axis-aligned trapezoid (the sim's camera 0.685 m in front of a face);
        # the general IPPE solves that one (but also "solves" corners on a line)
        x, y = pts[:, 0], pts[:, 1]
        if abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1))) < 2.0:   # twice the area, px^2
            return None
        for flags in (cv2.SOLVEPNP_IPPE_SQUARE, cv2.SOLVEPNP_IPPE):
            cands = self._candidates(pts, k, dist, flags)
            if cands:
                break
        else:
            return None
        cands.sort(key=lambda c: c[0])
        best = cands[0]
        if up is not None and len(cands) > 1:
            u = np.asarray(up, dtype=np.float64)
            u = u / np.linalg.norm(u)

            def upright(c):
                return float(cv2.Rodrigues(c[1])[0][:, 1] @ u)
            alt = cands[1]
            if upright(alt) > upright(best) and alt[0] < 2.0 * best[0] + 0.5:
                best = alt
        return best[1], best[2]

    def _candidates(self, pts, k, dist, flags) -> list:
        """(reprojection error, rvec, tvec) of each finite pose in front of the camera."""
        n, rvecs, tvecs, errs = cv2.solvePnPGeneric(self._obj, pts, k, dist, flags=flags)
        if not n or errs is None:          # degenerate corners (all on a line or one point): no pose
            return []
        return [(float(np.ravel(e)[0]), r, t) for r, t, e in zip(rvecs, tvecs, errs)
                if np.all(np.isfinite(r)) and np.all(np.isfinite(t)) and np.all(np.isfinite(e)) and t[2, 0] > 0]
