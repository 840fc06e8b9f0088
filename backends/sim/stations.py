"""Stations (MPS) in the world: body, slots, tags and signal tower.

Machine frame (as :mod:`rll_bt.rules.geometry`): x along the conveyor from
the output side (-x) to the input side (+x), y to the left, z up, origin at
the footprint centre on the floor.  The cabinet fills the 0.35 x 0.7 m
footprint up to 4 cm below the belt; on top run the conveyor and its guide
rails at ``belt_offset_y``, the cap station's shelf or the ring station's
slide sits on the input half at negative y, and the signal tower stands on a
control box on the output half.  A tag quad is centred under the belt on
each face, ``tag_centre_height`` above the floor.

Slots (where a workpiece can stand, surface height = belt height):
``input`` and ``output`` at the conveyor ends (3 cm inside the face), on a
CS also ``shelf0``..``shelf2`` (y = ``shelf_y``), on an RS ``slide``
(many workpieces).  A DS has only ``input``.

Lights: ``GREEN`` (bottom), ``YELLOW``, ``RED`` (top), each ``OFF``, ``ON``
or ``BLINK``; a blinking light is on during the first half of each period of
the world's blink frequency (2 Hz by default).  The tower is a grey core
cylinder (visible in the 5 mm unlit borders between the segments) carrying
three translucent coloured segments and the housing on top; an unlit
segment keeps its colour (tinted plastic), a lit one is drawn by the
camera renderer as an emitter (:mod:`backends.sim.render`, ``EMISSION``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rll_bt.backend import Pose2D, light_state_code, wrap_angle
from rll_bt.rules import CYAN, Profile, machine_team, machine_type

from .bullet import (
    Part,
    ShapeCache,
    box_polygon,
    matrix_quaternion,
    multibody,
    prism_mesh,
    pybullet,
    trimesh_shape,
    yaw_quaternion,
)
from .fieldgeom import footprint
from .layout import MachinePlacement
from .markers import quad_mesh, quad_size, texture_file

LIGHT_COLORS = ("GREEN", "YELLOW", "RED")        # tower bottom to top; bits 0, 1, 2
LIGHT_STATES = ("OFF", "ON", "BLINK")
SLOT_INSET = 0.03                                # slot centre inside the face, metres
SLIDE_CAPACITY = 10
RGBA_ON = {"GREEN": (0.05, 1.0, 0.05, 1.0), "YELLOW": (1.0, 0.85, 0.0, 1.0), "RED": (1.0, 0.05, 0.05, 1.0)}
# unlit: coloured translucent plastic, darker and less saturated than the lit light
RGBA_OFF = {"GREEN": (0.14, 0.42, 0.19, 1.0), "YELLOW": (0.62, 0.50, 0.12, 1.0), "RED": (0.55, 0.13, 0.11, 1.0)}
CORE_RGBA = (0.42, 0.42, 0.44, 1.0)             # the tower's core, seen in the unlit borders
HOUSING_RGBA = (0.16, 0.16, 0.17, 1.0)
CORE_RADIUS = 0.85                              # of the tower radius
TEAM_RGBA = {CYAN: (0.0, 0.75, 0.85, 1.0), "MAGENTA": (0.85, 0.0, 0.6, 1.0)}
CABINET_RGBA = (0.72, 0.72, 0.74, 1.0)
TAG_OFFSET = 0.002                               # quad in front of the face


@dataclass(frozen=True)
class Slot:
    name: str
    local: tuple[float, float, float]    # machine frame; z is the surface height
    capacity: int = 1


def blink_on(state: str, t: float, blink_hz: float) -> bool:
    """Whether a light in ``state`` is lit at time ``t``."""
    if state == "ON":
        return True
    if state == "BLINK":
        return int(math.floor(t * 2.0 * blink_hz + 1e-6)) % 2 == 0   # tolerate float sums of steps
    return False


class Station:
    """One MPS: pose, slots, tags and lights (its PyBullet body once built)."""

    def __init__(self, profile: Profile, placement: MachinePlacement):
        self.profile = profile
        self.placement = placement
        self.name = placement.machine
        self.team = machine_team(self.name)
        self.type = machine_type(self.name)
        self.pose = placement.pose
        self.zone = placement.zone
        self.rotation = placement.rotation_deg
        self.tag_ids = profile.tag_ids(self.name)
        self.box = footprint(profile, self.pose)
        self.lights = dict.fromkeys(LIGHT_COLORS, "OFF")
        self.slots = self._slots()
        self.body: int | None = None
        self._light_links: dict[str, int] = {}
        self.tower_links: set[int] = set()           # links of the signal tower (segments, core, housing)
        self.unlit_rgba = dict(RGBA_OFF)             # colour of each segment while unlit
        self._shown: dict[str, bool] = {}
        self._colours: dict[int, tuple] | None = None  # each link's colour, once the station was hidden
        self.visible = True                             # drawn in camera views (see set_visible)
        self._c, self._s = math.cos(self.pose.theta), math.sin(self.pose.theta)

    # -- geometry -----------------------------------------------------------
    def _slots(self) -> dict[str, Slot]:
        m = self.profile.mps
        x_in = m.depth / 2.0 - SLOT_INSET
        z = m.belt_height
        slots = {"input": Slot("input", (x_in, m.belt_offset_y, z))}
        if self.type != "DS":
            slots["output"] = Slot("output", (-x_in, m.belt_offset_y, z))
        if self.type == "CS":
            for i, y in enumerate(m.shelf_y):
                slots[f"shelf{i}"] = Slot(f"shelf{i}", (x_in, y, z))
        if self.type == "RS":
            slots["slide"] = Slot("slide", (x_in, m.slide_y, z), SLIDE_CAPACITY)
        return slots

    def to_world(self, x: float, y: float, z: float = 0.0) -> tuple[float, float, float]:
        """A machine-frame point in the field frame."""
        return (self.pose.x + self._c * x - self._s * y, self.pose.y + self._s * x + self._c * y, z)

    def direction(self, x: float, y: float) -> tuple[float, float]:
        """A machine-frame direction in the field frame."""
        return (self._c * x - self._s * y, self._s * x + self._c * y)

    def slot(self, name: str) -> Slot:
        try:
            return self.slots[name]
        except KeyError:
            raise KeyError(f"{self.name} has no slot {name!r} (slots: {', '.join(self.slots)})") from None

    def slot_point(self, name: str) -> tuple[float, float, float]:
        """Field-frame centre of the slot's surface (where a workpiece's bottom sits)."""
        return self.to_world(*self.slot(name).local)

    def approach_pose(self, slot: str, gap: float = 0.005) -> Pose2D:
        """Ground-truth robot pose facing the face of ``slot``, its body
        ``gap`` metres off the face and its centre in line with the slot, so
        the gripper at rest is over the slot."""
        x, y, _ = self.slot(slot).local
        sign = 1.0 if x > 0 else -1.0
        wx, wy, _ = self.to_world(sign * (self.profile.mps.depth / 2.0 + self.profile.robot.radius + gap), y)
        return Pose2D(wx, wy, wrap_angle(self.pose.theta + (math.pi if sign > 0 else 0.0)))

    def tag_id(self, side: str) -> int:
        return self.tag_ids[0 if side == "input" else 1]

    def tag_frame(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        """(centre, rotation) of the tag on ``side`` ("input" or "output") in
        the field frame; rotation columns are the marker's x (right), y (up)
        and z (out of the face) axes."""
        m = self.profile.mps
        sign = 1.0 if side == "input" else -1.0
        centre = np.array(self.to_world(sign * (m.depth / 2.0 + TAG_OFFSET), m.belt_offset_y,
                                        m.tag_centre_height))
        nx, ny = self.direction(sign, 0.0)
        z = np.array([nx, ny, 0.0])
        y = np.array([0.0, 0.0, 1.0])
        return centre, np.column_stack([np.cross(y, z), y, z])

    def tower_point(self, index: int = 1) -> tuple[float, float, float]:
        """Field-frame centre of light ``index`` (0 green, 1 yellow, 2 red)."""
        m = self.profile.mps
        return self.to_world(m.tower_x, m.tower_y, m.segment_centre_z(index))

    # -- lights -------------------------------------------------------------
    def set_lights(self, **states: str) -> None:
        for color, state in states.items():
            c, s = color.upper(), str(state).upper()
            if c not in LIGHT_COLORS:
                raise ValueError(f"unknown light {color!r} (known: RED, YELLOW, GREEN)")
            if s not in LIGHT_STATES:
                raise ValueError(f"unknown light state {state!r} (known: OFF, ON, BLINK)")
            self.lights[c] = s

    def light_code(self, t: float, blink_hz: float) -> int:
        """Lights visible at ``t`` as the paper's code (green 1, yellow 2, red 4)."""
        on = {c: blink_on(s, t, blink_hz) for c, s in self.lights.items()}
        return light_state_code(on["GREEN"], on["YELLOW"], on["RED"])

    def lit_links(self) -> dict[int, str]:
        """Links of the segments shown lit now -> light colour (``GREEN``...)."""
        return {self._light_links[c]: c for c, on in self._shown.items() if on}

    def show_lights(self, cid: int, t: float, blink_hz: float) -> None:
        """Colour the tower segments for time ``t`` (only segments that change)."""
        if self.body is None:
            return
        for c, state in self.lights.items():
            on = blink_on(state, t, blink_hz)
            if self._shown.get(c) != on:
                self._paint(cid, self._light_links[c], RGBA_ON[c] if on else self.unlit_rgba[c])
                self._shown[c] = on

    def set_unlit_colours(self, cid: int, rgba: dict[str, tuple]) -> None:
        """Recolour unlit segments (``{"GREEN": (r, g, b, a), ...}``, 0..1)."""
        self.unlit_rgba.update({c.upper(): tuple(v) for c, v in rgba.items()})
        if self.body is None:
            return
        for c, on in self._shown.items():
            if not on:
                self._paint(cid, self._light_links[c], self.unlit_rgba[c])

    def _paint(self, cid: int, link: int, rgba) -> None:
        """Give ``link`` the colour ``rgba`` (shown when the station is visible)."""
        if self._colours is not None:
            self._colours[link] = tuple(rgba)
        if self.visible:
            pybullet().changeVisualShape(self.body, link, rgbaColor=list(rgba), physicsClientId=cid)

    def set_visible(self, cid: int, visible: bool) -> None:
        """Show or hide the whole station in camera views (a hidden one costs a
        renderer nothing: :mod:`backends.sim.sparse` hides the stations a view
        cannot show).  Colours set while hidden apply when it shows again."""
        if self.body is None or visible == self.visible:
            return
        p = pybullet()
        if self._colours is None:
            self._colours = {int(d[1]): tuple(d[7]) for d in p.getVisualShapeData(self.body, physicsClientId=cid)}
        for link, rgba in self._colours.items():
            p.changeVisualShape(self.body, link, rgbaColor=list(rgba) if visible else [0.0, 0.0, 0.0, 0.0],
                                physicsClientId=cid)
        self.visible = visible

    # -- body ---------------------------------------------------------------
    def build(self, cid: int, shapes: ShapeCache, texture_dir: str | None = None) -> int:
        """Create the PyBullet body (cabinet with collision, the rest visual)."""
        p = pybullet()
        m = self.profile.mps
        top = m.belt_height - 0.04
        half = (m.depth / 2.0, m.width / 2.0, top / 2.0)
        zc = top / 2.0                         # link positions are relative to the cabinet centre
        parts: list[Part] = []

        def box(centre, half_ext, rgba) -> int:
            parts.append(Part(shapes.box(half_ext, rgba), (centre[0], centre[1], centre[2] - zc)))
            return len(parts) - 1

        belt_top = m.belt_height
        box((0.0, m.belt_offset_y, (top + belt_top) / 2.0),
            (m.depth / 2.0, 0.03, (belt_top - top) / 2.0), (0.12, 0.12, 0.12, 1.0))
        for side in (-1.0, 1.0):
            box((0.0, m.belt_offset_y + side * 0.035, (top + belt_top + 0.02) / 2.0),
                (m.depth / 2.0, 0.005, (belt_top + 0.02 - top) / 2.0), (0.55, 0.55, 0.58, 1.0))
        box((m.tower_x, m.tower_y, (top + m.tower_base) / 2.0),         # post under the tower
            (0.022, 0.022, (m.tower_base - top) / 2.0), (0.3, 0.3, 0.3, 1.0))
        for side in (-1.0, 1.0):
            box((0.0, side * (m.width / 2.0 + 0.001), top - 0.06),
                (m.depth / 2.0, 0.001, 0.03), TEAM_RGBA[self.team])
        if self.type == "CS":
            y0, y1 = min(m.shelf_y) - 0.04, min(max(m.shelf_y) + 0.04, m.width / 2.0)
            box((m.depth / 4.0, (y0 + y1) / 2.0, belt_top - 0.01),
                (m.depth / 4.0, (y1 - y0) / 2.0, 0.01), (0.6, 0.6, 0.64, 1.0))
        if self.type == "RS":
            box((m.depth / 4.0, m.slide_y, belt_top - 0.01),
                (m.depth / 4.0, 0.04, 0.01), (0.45, 0.45, 0.5, 1.0))
        seg_len = m.tower_segment - m.tower_segment_border
        core_len = 3 * m.tower_segment
        parts.append(Part(shapes.cylinder(m.tower_radius * CORE_RADIUS, core_len, CORE_RGBA),
                          (m.tower_x, m.tower_y, m.tower_base + core_len / 2.0 - zc)))
        self.tower_links = {len(parts) - 1}
        for i, c in enumerate(LIGHT_COLORS):
            parts.append(Part(shapes.cylinder(m.tower_radius, seg_len, RGBA_OFF[c]),
                              (m.tower_x, m.tower_y, m.segment_centre_z(i) - zc)))
            self._light_links[c] = len(parts) - 1
            self.tower_links.add(len(parts) - 1)
        parts.append(Part(shapes.cylinder(m.tower_radius, m.tower_cap, HOUSING_RGBA),
                          (m.tower_x, m.tower_y, m.tower_base + 3 * m.tower_segment
                           + m.tower_cap / 2.0 - zc)))
        self.tower_links.add(len(parts) - 1)
        tag_links = {}
        half_quad = quad_size(self.profile.tag_size) / 2.0
        quad = p.createVisualShape(p.GEOM_MESH, rgbaColor=[1, 1, 1, 1], physicsClientId=cid,
                                   **quad_mesh(half_quad))
        for side, sign in (("input", 1.0), ("output", -1.0)):
            z = (sign, 0.0, 0.0)
            rot = [[0.0, 0.0, z[0]], [sign, 0.0, 0.0], [0.0, 1.0, 0.0]]   # columns: x, y, z
            parts.append(Part(quad, (sign * (m.depth / 2.0 + TAG_OFFSET), m.belt_offset_y,
                                     m.tag_centre_height - zc), matrix_quaternion(rot)))
            tag_links[side] = len(parts) - 1
        self.body = multibody(
            cid, shapes.box(half, CABINET_RGBA), parts,
            base_collision=trimesh_shape(cid, [prism_mesh(box_polygon(half[0], half[1]), -half[2], half[2])]),
            position=(self.pose.x, self.pose.y, zc), orientation=yaw_quaternion(self.pose.theta))
        for side, link in tag_links.items():
            tex = p.loadTexture(texture_file(self.tag_id(side), texture_dir), physicsClientId=cid)
            p.changeVisualShape(self.body, link, textureUniqueId=tex, physicsClientId=cid)
        self._shown = dict.fromkeys(LIGHT_COLORS, False)
        self._colours, self.visible = None, True
        return self.body
