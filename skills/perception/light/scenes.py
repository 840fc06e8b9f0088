"""Labelled camera frames rendered from a simulated world.

Skills never import a backend by name: the world comes from the
``rll_bt.worlds`` entry point (``pybullet``: :func:`backends.sim.open_world`),
a factory ``(profile, seed, **options) -> world`` whose worlds render camera
views (``render_view``, ``tower_links``, ``backdrop_bodies``,
``set_lighting``, ``set_tower_look``, ``hall``; see
:mod:`backends.sim.camera`).  Every frame is rendered from a free camera
(any height, pitch, roll and field of view) under random lighting (colour
temperature, direction, intensity, exposure, bloom: ``Lighting.random``),
with the hall restyled and the towers' unlit tint and lit emission varied;
every signal tower in the frame is labelled from the renderer's
segmentation: its visible pixels, box and the light state set on its
station.

Field frame and units as :mod:`rll_bt.rules` (metres, radians).  Boxes are
(x, y, w, h) in pixels of the tower's visible silhouette.
"""
from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass, field

import numpy as np

from rll_bt import plugins
from rll_bt.backend import CameraIntrinsics, light_state_code
from rll_bt.errors import UserError

NEAR = 0.02
LIGHTS = ("GREEN", "YELLOW", "RED")
WORLDS = "rll_bt.worlds"
#: hue (0..1) of each light's plastic: green, yellow, red
_HUES = {"GREEN": 0.37, "YELLOW": 0.13, "RED": 0.0}
#: linear emission (R, G, B) of each lit light around which training varies
_EMISSION = {"GREEN": (0.28, 1.9, 0.38), "YELLOW": (2.1, 1.45, 0.12), "RED": (2.3, 0.22, 0.14)}


def world_factory(name: str = "pybullet"):
    """The world factory ``name`` of the ``rll_bt.worlds`` entry points."""
    try:
        return plugins.load(WORLDS, name)
    except KeyError as exc:
        raise UserError(str(exc.args[0]), hint="rendering training data needs the PyBullet sim "
                        "(the rll_bt.worlds entry point 'pybullet' of rll-bt)") from None


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
    sky: np.ndarray | None = None    # bool mask of the backdrop (hall, or nothing rendered)

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

    ``world`` comes from a :func:`world_factory` (see the module for what it
    must offer); ``rng`` drives every random choice.
    """

    def __init__(self, world, rng: np.random.Generator, views: ViewRange = ViewRange()):
        self.world = world
        self.rng = rng
        self.views = views
        self.mps = world.profile.mps
        self._tower_links = {name: world.tower_links(name) for name in world.machines}
        self._backdrop = np.asarray(world.backdrop_bodies(), np.int64)
        f = world.profile.field
        self._field = (f.x_min, f.y_min, f.x_max, f.y_max)

    def randomise_look(self) -> None:
        """Random lighting, hall textures, unlit tint (hue kept, strength and
        shade varied) and lit emission (brightness varied)."""
        w, rng = self.world, self.rng
        w.set_lighting(w.lighting.random(rng))
        w.hall.restyle(rng)
        unlit = {}
        for c in LIGHTS:
            h = (_HUES[c] + rng.uniform(-0.03, 0.03)) % 1.0
            r, g, b = colorsys.hsv_to_rgb(h, rng.uniform(0.45, 0.9), rng.uniform(0.2, 0.6))
            unlit[c] = (r, g, b, 1.0)
        gain = rng.uniform(0.75, 1.5)
        emission = {c: tuple(float(v) * gain * rng.uniform(0.85, 1.15) for v in base)
                    for c, base in _EMISSION.items()}
        w.set_tower_look(unlit=unlit, emission=emission)

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
        view = self.world.render_view(np.asarray(eye, float), rot, intr)
        seg = view.seg
        body, link = view.body, view.link
        frame = Frame(view.image, intr, eye=tuple(float(v) for v in eye),
                      sky=(seg < 0) | np.isin(body, self._backdrop))
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

    @staticmethod
    def _silhouette_area(full) -> float:
        """Pixels of an unoccluded tower: its outline (segments, the core in
        the borders between them, the housing) nearly fills the box."""
        x0, y0, x1, y1 = full
        return 0.92 * (x1 - x0) * (y1 - y0)

    def sample(self, tower: bool = True) -> Frame | None:
        """One random frame: showing a tower (``tower``) or none at all."""
        states = self.randomise_lights()
        self.randomise_look()
        view = self.tower_view() if tower else self.free_view()
        if view is None:
            return None
        return self.render(*view, states)
