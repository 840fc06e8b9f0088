"""Labelled camera frames rendered from the PyBullet world.

Skills never import a backend by name: the world class is found through
the ``sim`` backend plug-in (``rll_bt.backends`` entry point), whose module
exports ``World``.  Frames are rendered with PyBullet's TinyRenderer from a
free camera (any height, pitch, roll and field of view, random light
direction and strength), and every signal tower in the frame is labelled
from the renderer's segmentation mask: its visible pixels, box and the
light state set on its station.

Field frame and units as :mod:`rll_bt.rules` (metres, radians).  Boxes are
(x, y, w, h) in pixels of the tower's visible silhouette.
"""
from __future__ import annotations

import importlib
import math
from dataclasses import dataclass, field

import numpy as np

from rll_bt import plugins
from rll_bt.backend import CameraIntrinsics, light_state_code
from rll_bt.errors import UserError

NEAR, FAR = 0.02, 25.0
LIGHTS = ("GREEN", "YELLOW", "RED")


def sim_world_class():
    """The PyBullet world class of the installed ``sim`` backend plug-in."""
    try:
        factory = plugins.load("rll_bt.backends", "sim")
    except KeyError as exc:
        raise UserError(str(exc.args[0]), hint="rendering training data needs the PyBullet 'sim' backend") from None
    module = importlib.import_module(factory.__module__)
    world = getattr(module, "World", None)
    if world is None:
        raise UserError(f"the sim backend plug-in ({factory.__module__}) exports no World class")
    return world


@dataclass
class TowerLabel:
    machine: str
    state: int                       # 0..7, green 1, yellow 2, red 4
    box: tuple[int, int, int, int]   # visible silhouette, pixels
    full_box: tuple[int, int, int, int] | None   # the whole tower projected; None when cut by the frame edge
    visible: float                   # visible pixels / pixels of the unoccluded tower
    distance: float                  # camera to tower axis, horizontal, metres
    mask: np.ndarray | None = None   # bool mask of the tower pixels inside ``box``
    region: tuple[int, int, int, int] | None = None   # where its tag says the tower is
    tower_height: float | None = None                  # the tower's height there, pixels
    roi: tuple[int, int, int, int] | None = None       # the tower's box by the same tag pose, no margin

    @property
    def clean(self) -> bool:
        """Fully visible and inside the frame: a tower a detector must find."""
        return self.full_box is not None and self.visible >= 0.85


@dataclass
class Frame:
    image: np.ndarray                # H x W x 3 BGR uint8
    intrinsics: CameraIntrinsics
    towers: list[TowerLabel] = field(default_factory=list)
    eye: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sky: np.ndarray | None = None    # bool mask of the pixels where nothing was rendered

    @property
    def tower_free(self) -> bool:
        return not self.towers


@dataclass(frozen=True)
class ViewRange:
    """What random views are drawn from."""
    distance: tuple[float, float] = (0.5, 2.5)        # camera to tower axis, horizontal
    height: tuple[float, float] = (0.45, 1.3)         # camera above the floor
    hfov: tuple[float, float] = (0.9, 1.25)           # horizontal field of view, rad
    roll_deg: float = 4.0
    size: tuple[int, int] = (640, 480)


def _look_rotation(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Optical-frame axes (columns x right, y down, z forward) in the field
    frame for a camera looking along ``yaw`` (about z), ``pitch`` (up
    positive) and ``roll`` about the viewing axis."""
    fwd = np.array([math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)])
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.cross(fwd, right)
    c, s = math.cos(roll), math.sin(roll)
    r2, d2 = c * right + s * down, -s * right + c * down
    return np.column_stack([r2, d2, fwd])


class SceneRenderer:
    """Renders labelled frames of one world (a layout of a profile).

    ``world`` is a ``World`` of the sim plug-in (or anything with its
    station API: ``cid``, ``machines``, ``station(name)``, ``set_lights``,
    ``profile``).  ``rng`` drives every random choice.
    """

    def __init__(self, world, rng: np.random.Generator, views: ViewRange = ViewRange()):
        import pybullet
        self.p = pybullet
        self.world = world
        self.rng = rng
        self.views = views
        self.mps = world.profile.mps
        self._tower_links = {name: self._find_tower_links(world.station(name)) for name in world.machines}
        self._body_machine = {world.station(n).body: n for n in world.machines}
        f = world.profile.field
        self._field = (f.x_min, f.y_min, f.x_max, f.y_max)

    def _find_tower_links(self, station) -> set[int]:
        r = self.mps.tower_radius
        links = set()
        for shape in self.p.getVisualShapeData(station.body, physicsClientId=self.world.cid):
            link, geom, dims = shape[1], shape[2], shape[3]
            if geom == self.p.GEOM_CYLINDER and abs(dims[1] - r) < 1e-4:
                links.add(link)
        if not links:
            raise RuntimeError(f"no signal tower found on station {station.name}")
        return links

    # -- the scene ----------------------------------------------------------
    def randomise_lights(self) -> dict[str, int]:
        """Give every station a random steady state; returns name -> 0..7."""
        states = {}
        for name in self.world.machines:
            s = int(self.rng.integers(0, 8))
            on = [(s >> i) & 1 for i in range(3)]
            self.world.set_lights(name, green="ON" if on[0] else "OFF", yellow="ON" if on[1] else "OFF",
                                  red="ON" if on[2] else "OFF")
            st = self.world.station(name)
            st.show_lights(self.world.cid, self.world.time, self.world.blink_hz)
            states[name] = light_state_code(*(bool(b) for b in on))
        return states

    def _free_spot(self, x: float, y: float, margin: float = 0.3) -> bool:
        x0, y0, x1, y1 = self._field
        if not (x0 + margin < x < x1 - margin and y0 + margin < y < y1 - margin):
            return False
        for name in self.world.machines:
            st = self.world.station(name)
            local_c, local_s = math.cos(-st.pose.theta), math.sin(-st.pose.theta)
            dx, dy = x - st.pose.x, y - st.pose.y
            lx, ly = local_c * dx - local_s * dy, local_s * dx + local_c * dy
            if abs(lx) < self.mps.depth / 2 + margin and abs(ly) < self.mps.width / 2 + margin:
                return False
        return True

    def tower_view(self, machine: str | None = None, tries: int = 50):
        """A random camera (eye, rotation, intrinsics) with ``machine``'s tower
        (random when None) somewhere in the frame, or None."""
        v, rng = self.views, self.rng
        for _ in range(tries):
            name = machine or self.world.machines[int(rng.integers(len(self.world.machines)))]
            st = self.world.station(name)
            tower = np.array(st.tower_point(1))
            d = rng.uniform(*v.distance)
            a = rng.uniform(-math.pi, math.pi)
            ex, ey = tower[0] + d * math.cos(a), tower[1] + d * math.sin(a)
            if not self._free_spot(ex, ey):
                continue
            eye = np.array([ex, ey, rng.uniform(*v.height)])
            hfov = rng.uniform(*v.hfov)
            intr = CameraIntrinsics.from_fov(v.size[0], v.size[1], hfov)
            vfov = 2 * math.atan(intr.height / 2 / intr.fy)
            to = tower - eye
            yaw = math.atan2(to[1], to[0]) + rng.uniform(-0.8, 0.8) * hfov / 2
            pitch = math.atan2(to[2], math.hypot(to[0], to[1])) + rng.uniform(-0.7, 0.7) * vfov / 2
            roll = math.radians(rng.uniform(-v.roll_deg, v.roll_deg))
            return eye, _look_rotation(yaw, pitch, roll), intr
        return None

    def free_view(self, tries: int = 200):
        """A random camera whose frame shows no signal tower at all, or None."""
        v, rng = self.views, self.rng
        x0, y0, x1, y1 = self._field
        for _ in range(tries):
            ex, ey = rng.uniform(x0, x1), rng.uniform(y0, y1)
            if not self._free_spot(ex, ey):
                continue
            eye = np.array([ex, ey, rng.uniform(*v.height)])
            intr = CameraIntrinsics.from_fov(v.size[0], v.size[1], rng.uniform(*v.hfov))
            rot = _look_rotation(rng.uniform(-math.pi, math.pi), rng.uniform(-0.5, 0.35),
                                 math.radians(rng.uniform(-v.roll_deg, v.roll_deg)))
            if not any(self._projected_box(self.world.station(n), eye, rot, intr, margin=4) is not None
                       for n in self.world.machines):
                return eye, rot, intr
        return None

    def _projected_box(self, st, eye, rot, intr: CameraIntrinsics, margin: int = 0):
        """Box of the whole tower in the image (clipped), None when outside."""
        m = self.mps
        bx, by, _ = st.tower_point(0)
        pts = []
        for z in (m.tower_base, m.tower_base + m.tower_height):
            for ang in np.linspace(0, 2 * math.pi, 8, endpoint=False):
                pts.append((bx + m.tower_radius * math.cos(ang), by + m.tower_radius * math.sin(ang), z))
        cam = (np.asarray(pts) - eye) @ rot
        if np.any(cam[:, 2] < NEAR):
            return None
        u = intr.fx * cam[:, 0] / cam[:, 2] + intr.cx
        v = intr.fy * cam[:, 1] / cam[:, 2] + intr.cy
        x0, x1, y0, y1 = u.min(), u.max(), v.min(), v.max()
        if x1 < -margin or y1 < -margin or x0 > intr.width + margin or y0 > intr.height + margin:
            return None
        if cam[:, 2].min() > 12.0:
            return None
        return (x0, y0, x1, y1)

    # -- rendering ----------------------------------------------------------
    def render(self, eye, rot, intr: CameraIntrinsics, states: dict[str, int]) -> Frame:
        p, rng = self.p, self.rng
        cid = self.world.cid
        view = p.computeViewMatrix(list(eye), list(eye + rot[:, 2]), list(-rot[:, 1]), physicsClientId=cid)
        vfov = math.degrees(2.0 * math.atan(intr.height / (2.0 * intr.fy)))
        proj = p.computeProjectionMatrixFOV(vfov, intr.width / intr.height, NEAR, FAR, physicsClientId=cid)
        el, az = rng.uniform(0.3, 1.4), rng.uniform(-math.pi, math.pi)
        light_dir = [math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]
        tint = rng.uniform(0.85, 1.0, 3)
        _, _, rgba, _, seg = p.getCameraImage(
            intr.width, intr.height, view, proj, shadow=0, renderer=p.ER_TINY_RENDERER,
            lightDirection=light_dir, lightColor=tint.tolist(), lightAmbientCoeff=rng.uniform(0.35, 0.75),
            lightDiffuseCoeff=rng.uniform(0.3, 0.7), lightSpecularCoeff=rng.uniform(0.0, 0.3),
            flags=p.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX, physicsClientId=cid)
        rgb = np.reshape(np.asarray(rgba, dtype=np.uint8), (intr.height, intr.width, 4))[:, :, :3]
        seg = np.reshape(np.asarray(seg, dtype=np.int64), (intr.height, intr.width))
        frame = Frame(np.ascontiguousarray(rgb[:, :, ::-1]), intr, eye=tuple(float(v) for v in eye),
                      sky=seg < 0)
        body = np.where(seg >= 0, seg & ((1 << 24) - 1), -1)
        link = np.where(seg >= 0, (seg >> 24) - 1, -2)
        for name in self.world.machines:
            st = self.world.station(name)
            full = self._projected_box(st, eye, rot, intr)
            if full is None:
                continue
            mask = (body == st.body) & np.isin(link, list(self._tower_links[name]))
            if not mask.any():
                continue
            ys, xs = np.nonzero(mask)
            box = (int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1))
            fx0, fy0, fx1, fy1 = full
            inside = fx0 >= 0 and fy0 >= 0 and fx1 < intr.width and fy1 < intr.height
            full_box = (int(round(fx0)), int(round(fy0)), int(round(fx1 - fx0)), int(round(fy1 - fy0)))
            tp = np.array(st.tower_point(1))
            where = self.tag_region(st, eye, rot, intr)
            frame.towers.append(TowerLabel(
                name, states[name], box, full_box if inside else None,
                min(1.0, float(mask.sum()) / max(self._silhouette_area(full), 1.0)),
                float(math.hypot(tp[0] - eye[0], tp[1] - eye[1])),
                mask[box[1]:box[1] + box[3], box[0]:box[0] + box[2]].copy(),
                *(where if where is not None else (None, None, None))))
        return frame

    def tag_region(self, st, eye, rot, intr: CameraIntrinsics, pos_sigma: float = 0.01,
                   rot_sigma: float = math.radians(1.5)):
        """(search region, tower height, tight tower box) the station's tag
        facing the camera would give (:func:`.region.tower_region`), from its
        true pose in the camera frame with tag-detection noise: position
        ``pos_sigma`` per metre of range, rotation ``rot_sigma``."""
        import cv2
        from rll_bt.backend import TagDetection
        from .region import tower_region
        best = None
        for side in ("input", "output"):
            centre, frame = st.tag_frame(side)
            facing = float(frame[:, 2] @ (eye - centre))
            if best is None or facing > best[0]:
                best = (facing, side, centre, frame)
        _, side, centre, frame = best
        t = (centre - eye) @ rot
        t = t + self.rng.normal(0.0, pos_sigma * float(np.linalg.norm(t)), 3)
        jitter, _ = cv2.Rodrigues(self.rng.normal(0.0, rot_sigma, 3).reshape(3, 1))
        rvec, _ = cv2.Rodrigues(jitter @ (rot.T @ frame))
        det = TagDetection(st.tag_id(side), tuple(float(v) for v in t), tuple(float(v) for v in rvec.ravel()))
        where = tower_region(det, side.upper(), self.mps, intr)
        tight = tower_region(det, side.upper(), self.mps, intr, margin_x=0.0, margin_y=0.0, min_size=0)
        if where is None or tight is None:
            return None
        return where[0], where[1], tight[0]

    def _silhouette_area(self, full) -> float:
        """Pixels of an unoccluded tower: its outline nearly fills the box,
        less the unlit borders between the segments, which show the background."""
        x0, y0, x1, y1 = full
        m = self.mps
        solid = 1.0 - 3 * m.tower_segment_border / m.tower_height
        return 0.93 * solid * (x1 - x0) * (y1 - y0)

    def sample(self, tower: bool = True) -> Frame | None:
        """One random frame: showing a tower (``tower``) or none at all."""
        states = self.randomise_lights()
        view = self.tower_view() if tower else self.free_view()
        if view is None:
            return None
        return self.render(*view, states)
