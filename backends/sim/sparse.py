"""Robots' camera frames rendered where something can be detected.

A game with rendered perception takes a frame from every robot's camera on
every tree tick; rendering each whole at full resolution made such a game
run at about real time.  A robot's frame (:func:`sparse_frame`) is made of

- the whole view at an eighth of the resolution in each direction
  (:data:`BACKGROUND_DIVISOR`), enlarged: the hall, the floor, far
  stations and robots, where nothing could be detected anyway;
- for every station near enough for its tags to be read (a tag at least
  :data:`MIN_TAG_PIXELS` wide at full resolution: about 3.6 m for a
  320 x 240 camera) a window round each tag that faces the camera and one
  round its signal tower, wider than the region a light reader searches
  (:func:`station_windows`; windows that touch are merged), rendered at
  full resolution, pixel for pixel what the whole view would show there,
  or, when the station is so near that its tags would be more than
  :data:`DETAIL_TAG_PIXELS` wide, at a half or a third of it (a detector
  needs no more);
- when nothing the frame shows changed since that robot's last frame
  (:func:`frame_key`: the camera pose to a millimetre and a tenth of a
  milliradian, the lights of the stations in view, the poses of the other
  robots near enough to show, the lighting), the last frame's image again
  (the same array, so a detector can tell it has seen it); a frame with no
  station near enough is made again only when the camera has moved
  :data:`EMPTY_MOVE` metres or :data:`EMPTY_TURN` radians or
  :data:`EMPTY_AGE` seconds have passed (nothing in it could be detected).

Tags, and towers where a tag puts them, are all the detectors look for
(``skills.perception.source``; the light reader searches the whole frame
only when asked to, and then the towers of far stations are too small to
read anyway), so the detections on a sparse frame are those of a whole
frame rendered at full resolution, up to the few pixels of a window's
border.
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from rll_bt.backend import CameraIntrinsics

from .markers import quad_size
from .render import NEAR

BACKGROUND_DIVISOR = 8
MIN_TAG_PIXELS = 10.0
DETAIL_TAG_PIXELS = 28.0        # a nearer station's window is rendered at a half or a third
EMPTY_MOVE, EMPTY_TURN, EMPTY_AGE = 0.25, 0.15, 1.0
WINDOW_PAD = 4                  # pixels around what a window must hold
TAG_GROW = 1.25                 # a tag's window: its white quad grown by this much
#: a tower's window: its outline grown by these tower widths to each side and heights above and below
#: (more than a reader searches round it: :func:`skills.perception.light.region.tower_region`)
TOWER_MARGIN = (2.0, 0.7)
MERGE_GAP = 8                   # windows this close are rendered as one
FULL_SHARE = 0.6                # windows covering more of the frame: render it whole


class SparseScene:
    """The stations' geometry a sparse frame needs, in arrays (stations never move)."""

    def __init__(self, stations):
        self.stations = list(stations)
        n = len(self.stations)
        towers, cabinets, corners, normals = [], [], [], []
        for st in self.stations:
            m = st.profile.mps
            ring = [(m.tower_x + m.tower_radius * math.cos(a), m.tower_y + m.tower_radius * math.sin(a))
                    for a in np.linspace(0.0, 2 * math.pi, 8, endpoint=False)]
            towers.append([st.to_world(x, y, z) for z in (m.tower_base, m.tower_base + m.tower_height)
                           for x, y in ring])
            cabinets.append([st.to_world(sx * m.depth / 2, sy * m.width / 2, z) for sx in (-1, 1) for sy in (-1, 1)
                             for z in (0.0, m.belt_height + 0.03)])
            half = quad_size(st.profile.tag_size) / 2.0 * TAG_GROW
            for side in ("input", "output"):
                centre, frame = st.tag_frame(side)
                x, y = frame[:, 0] * half, frame[:, 1] * half
                corners.append([centre - x + y, centre + x + y, centre + x - y, centre - x - y])
                normals.append(frame[:, 2])
        self.tower = np.asarray(towers, float).reshape(n, 16, 3)
        self.outline = np.concatenate([np.asarray(cabinets, float).reshape(n, 8, 3), self.tower], axis=1)
        self.tag_corners = np.asarray(corners, float).reshape(n, 2, 4, 3)
        self.tag_normal = np.asarray(normals, float).reshape(n, 2, 3)
        self.tag_centre = self.tag_corners.mean(axis=2)
        self.tag_size = self.stations[0].profile.tag_size if n else 0.0
        self.width = self.stations[0].profile.mps.width if n else 0.0


def scene(world) -> SparseScene:
    sc = getattr(world, "_sparse_scene", None)
    if sc is None:
        sc = world._sparse_scene = SparseScene(world._station_list)
    return sc


def detail_range(intr: CameraIntrinsics, tag_size: float) -> float:
    """Distance (m) up to which a station's tags show at least :data:`MIN_TAG_PIXELS` wide."""
    return intr.fx * tag_size / MIN_TAG_PIXELS


def _overlaps(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _project_boxes(pts: np.ndarray, eye: np.ndarray, rot: np.ndarray, intr: CameraIntrinsics) -> np.ndarray:
    """Pixel boxes (x0, y0, x1, y1) of point sets ``pts`` (... x k x 3): NaN
    where all points are behind the camera, the whole frame where some are."""
    cam = (pts - eye) @ rot
    z = cam[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = intr.fx * cam[..., 0] / z + intr.cx
        v = intr.fy * cam[..., 1] / z + intr.cy
    out = np.stack([u.min(axis=-1), v.min(axis=-1), u.max(axis=-1), v.max(axis=-1)], axis=-1)
    behind = z < NEAR
    out[behind.any(axis=-1)] = (0.0, 0.0, float(intr.width), float(intr.height))
    out[behind.all(axis=-1)] = np.nan
    return out


def station_windows(sc: SparseScene, eye: np.ndarray, rot: np.ndarray, intr: CameraIntrinsics,
                    max_range: float) -> tuple[list[tuple[int, int, int, int, int]], list]:
    """(windows (x, y, w, h, divisor) to render, the stations in them) for
    the stations within ``max_range`` of ``eye`` whose tower or a tag facing
    the camera shows in the frame: a window round each such tag (its white
    quad and a margin) and round the tower with :data:`TOWER_MARGIN`
    (where a reader searches for it; the tag's pose puts it there to a few
    pixels), at 1/divisor of the resolution (see the module)."""
    if not sc.stations:
        return [], []
    near = np.hypot(sc.tower[:, :, 0] - eye[0], sc.tower[:, :, 1] - eye[1]).min(axis=1)
    tag_dist = np.hypot(sc.tag_centre[:, :, 0] - eye[0], sc.tag_centre[:, :, 1] - eye[1])
    facing = ((eye - sc.tag_centre) * sc.tag_normal).sum(axis=2) > 0.0
    tag_ok = facing & (tag_dist <= max_range)
    tower_ok = near <= max_range
    candidates = np.flatnonzero(tower_ok | tag_ok.any(axis=1))
    boxes, shown = [], []
    if len(candidates):
        tags = _project_boxes(sc.tag_corners[candidates], eye, rot, intr)        # c x 2 x 4
        towers = _project_boxes(sc.tower[candidates], eye, rot, intr)            # c x 4
        tag_cut = (((sc.tag_corners[candidates] - eye) @ rot[:, 2]) < NEAR).any(axis=2)
        tower_cut = (((sc.tower[candidates] - eye) @ rot[:, 2]) < NEAR).any(axis=1)
    for k, i in enumerate(candidates):
        div = int(np.clip(intr.fx * sc.tag_size / max(float(near[i]), 1e-3) // DETAIL_TAG_PIXELS, 1, 3))
        # a tag or tower reaching behind the camera cannot be whole in the frame: nothing to detect
        found = [tags[k, j] + (-WINDOW_PAD, -WINDOW_PAD, WINDOW_PAD, WINDOW_PAD)
                 for j in range(2) if tag_ok[i, j] and not tag_cut[k, j]]
        if tower_ok[i] and not tower_cut[k]:
            b = towers[k]
            mx = TOWER_MARGIN[0] * (b[2] - b[0]) + WINDOW_PAD
            my = TOWER_MARGIN[1] * (b[3] - b[1]) + WINDOW_PAD
            found.append(b + (-mx, -my, mx, my))
        kept = 0
        for b in found:
            x0, y0 = max(0, int(math.floor(b[0]))), max(0, int(math.floor(b[1])))
            x1, y1 = min(intr.width, int(math.ceil(b[2]))), min(intr.height, int(math.ceil(b[3])))
            if x1 - x0 >= 2 and y1 - y0 >= 2:
                boxes.append([x0, y0, x1, y1, div])
                kept += 1
        if kept:
            shown.append(sc.stations[i])
    merged = True
    while merged:                                 # merge windows that touch
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                if a[0] <= b[2] + MERGE_GAP and b[0] <= a[2] + MERGE_GAP and \
                        a[1] <= b[3] + MERGE_GAP and b[1] <= a[3] + MERGE_GAP:
                    boxes[i] = [min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]), min(a[4], b[4])]
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    out = []
    for x0, y0, x1, y1, div in boxes:             # a divided window starts and ends on whole low-res pixels
        x0, y0 = x0 - x0 % div, y0 - y0 % div
        x1, y1 = min(intr.width, x1 + (-x1) % div), min(intr.height, y1 + (-y1) % div)
        out.append((x0, y0, x1 - x0, y1 - y0, div))
    return out, shown


def _scaled(intr: CameraIntrinsics, k: int) -> CameraIntrinsics:
    return CameraIntrinsics(intr.width // k, intr.height // k, intr.fx / k, intr.fy / k, intr.cx / k, intr.cy / k,
                            intr.distortion)


def frame_key(world, robot, eye: np.ndarray, rot: np.ndarray, shown, max_range: float) -> tuple:
    """What a frame shows, coarsely: equal keys, equal frames (see the module)."""
    others = []
    for r in world.robots.values():
        if r is robot:
            continue
        if math.hypot(r.pose.x - eye[0], r.pose.y - eye[1]) <= max_range + 1.0:
            others.append((r.team, r.number, round(r.pose.x, 3), round(r.pose.y, 3), round(r.pose.theta, 3)))
    return (tuple(np.round(eye, 3)), tuple(np.round(rot, 4).ravel()),
            tuple((st.name, tuple(sorted(st.lit_links()))) for st in shown), tuple(others),
            world.lighting, id(world._emission))


def sparse_frame(world, robot, eye: np.ndarray, rot: np.ndarray, intr: CameraIntrinsics,
                 last: tuple | None) -> tuple[tuple, np.ndarray, tuple | None]:
    """(key, BGR image, where and when a frame with no station was made) of
    ``robot``'s frame; ``last`` is its previous one, handed back when
    nothing changed (see the module)."""
    world._show_lights()
    sc = scene(world)
    max_range = detail_range(intr, sc.tag_size)
    windows, shown = station_windows(sc, eye, rot, intr, max_range)
    key = frame_key(world, robot, eye, rot, shown, max_range)
    if last is not None and last[0] == key:
        return last
    if not windows and last is not None and last[2] is not None:
        eye0, fwd0, t0 = last[2]
        turn = math.acos(float(np.clip(rot[:, 2] @ fwd0, -1.0, 1.0)))
        if np.linalg.norm(eye - eye0) < EMPTY_MOVE and turn < EMPTY_TURN and world.time - t0 < EMPTY_AGE:
            return last
    # what each station covers in the frame: a render draws only the stations that can show in it
    frame = (0.0, 0.0, float(intr.width), float(intr.height))
    outlines = _project_boxes(sc.outline, eye, rot, intr) if sc.stations else np.zeros((0, 4))
    boxes = {st.name: b for st, b in zip(sc.stations, outlines) if not np.isnan(b[0]) and _overlaps(b, frame)}

    def drawn(window):
        return {n for n, b in boxes.items() if _overlaps(b, window)}

    full = [w for w in windows if w[4] == 1]
    if sum(w[2] * w[3] for w in full) > FULL_SHARE * intr.width * intr.height:
        return key, world.render_view(eye, rot, intr, stations=set(boxes)).image, None
    k = BACKGROUND_DIVISOR
    image = cv2.resize(world.render_view(eye, rot, _scaled(intr, k), stations=set(boxes)).image,
                       (intr.width, intr.height), interpolation=cv2.INTER_LINEAR)
    for x, y, w, h, div in windows:
        show = drawn((x - 1, y - 1, x + w + 1, y + h + 1))
        if div == 1 or w < div or h < div:        # (a sliver narrower than its divisor: at full resolution)
            image[y:y + h, x:x + w] = world.render_view(eye, rot, intr, window=(x, y, w, h), stations=show).image
        else:
            part = world.render_view(eye, rot, _scaled(intr, div), window=(x // div, y // div, w // div, h // div),
                                     stations=show)
            image[y:y + h, x:x + w] = cv2.resize(part.image, (w, h), interpolation=cv2.INTER_LINEAR)
    empty = (eye.copy(), rot[:, 2].copy(), world.time) if not windows else None
    return key, image, empty
