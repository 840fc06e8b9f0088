"""Thin helpers around PyBullet: a quiet import, connecting a client, and
building static multi-part bodies.

Every call passes ``physicsClientId`` explicitly, so several worlds can live
in one process.  Frames: PyBullet world = field frame (x, y as the rules
profile, z up, metres).
"""
from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass

from rll_bt.backend import BackendUnavailable

_pb = None
IDENTITY = (0.0, 0.0, 0.0, 1.0)


def pybullet():
    """The ``pybullet`` module, imported once without the build-time banner
    its C module prints (on stderr) when first imported."""
    global _pb
    if _pb is None:
        try:
            sys.stderr.flush()
            saved = os.dup(2)
        except (OSError, ValueError):      # no real stderr: import as is
            import pybullet as pb
            _pb = pb
            return _pb
        try:
            with open(os.devnull, "w") as devnull:
                os.dup2(devnull.fileno(), 2)
                import pybullet as pb
                _flush_c_stdio()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        _pb = pb
    return _pb


def _flush_c_stdio() -> None:
    """Flush C's stdio buffers while the banner's stream is redirected."""
    try:
        import ctypes
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


def display_available() -> bool:
    """Whether a GUI window could be opened (an X11 or Wayland display)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def connect(gui: bool = False) -> int:
    """A new physics client: DIRECT (headless) by default, GUI on request.

    Raises :class:`BackendUnavailable` when a GUI is asked for and no display
    exists."""
    p = pybullet()
    if gui:
        if not display_available():
            raise BackendUnavailable("cannot open the PyBullet window: no display "
                                     "(DISPLAY/WAYLAND_DISPLAY unset); run without --gui")
        cid = p.connect(p.GUI)
    else:
        cid = p.connect(p.DIRECT)
    if cid < 0:
        raise BackendUnavailable("cannot connect to PyBullet")
    return cid


def yaw_quaternion(theta: float) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation by ``theta`` radians about z."""
    return (0.0, 0.0, math.sin(theta / 2.0), math.cos(theta / 2.0))


@dataclass(frozen=True)
class Part:
    """One visual piece of a static body, placed in the body's frame."""
    visual: int
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float] = IDENTITY


class ShapeCache:
    """Visual shapes by (kind, size, colour), created once per client:
    PyBullet never frees shapes, so a world that respawns workpieces must
    reuse them."""

    def __init__(self, cid: int):
        self.cid = cid
        self._shapes: dict[tuple, int] = {}

    def box(self, half: tuple[float, float, float], rgba) -> int:
        key = ("box", tuple(round(h, 5) for h in half), tuple(rgba))
        if key not in self._shapes:
            p = pybullet()
            self._shapes[key] = p.createVisualShape(p.GEOM_BOX, halfExtents=list(half),
                                                    rgbaColor=list(rgba), physicsClientId=self.cid)
        return self._shapes[key]

    def cylinder(self, radius: float, length: float, rgba) -> int:
        key = ("cyl", round(radius, 5), round(length, 5), tuple(rgba))
        if key not in self._shapes:
            p = pybullet()
            self._shapes[key] = p.createVisualShape(p.GEOM_CYLINDER, radius=radius, length=length,
                                                    rgbaColor=list(rgba), physicsClientId=self.cid)
        return self._shapes[key]


def multibody(cid: int, base_visual: int, parts: list[Part], *, base_collision: int = -1,
              position=(0.0, 0.0, 0.0), orientation=IDENTITY, mass: float = 0.0) -> int:
    """A body made of a base shape plus fixed visual-only links (``parts``).

    Link ``i`` of the body is ``parts[i]``, so its colour or texture can be
    changed later with ``changeVisualShape(body, i, ...)``."""
    p = pybullet()
    n = len(parts)
    return p.createMultiBody(
        baseMass=mass, baseCollisionShapeIndex=base_collision, baseVisualShapeIndex=base_visual,
        basePosition=list(position), baseOrientation=list(orientation),
        linkMasses=[0.0] * n, linkCollisionShapeIndices=[-1] * n,
        linkVisualShapeIndices=[q.visual for q in parts],
        linkPositions=[list(q.position) for q in parts],
        linkOrientations=[list(q.orientation) for q in parts],
        linkInertialFramePositions=[[0.0, 0.0, 0.0]] * n,
        linkInertialFrameOrientations=[list(IDENTITY)] * n,
        linkParentIndices=[0] * n, linkJointTypes=[p.JOINT_FIXED] * n,
        linkJointAxis=[[0.0, 0.0, 1.0]] * n, physicsClientId=cid)


def matrix_quaternion(m) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a 3x3 rotation matrix (rows of floats)."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    if m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        return (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    if m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        return ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    s = math.sqrt(1.0 + m22 - m00 - m11) * 2
    return ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)


def prism_mesh(polygon, z0: float, z1: float) -> tuple[list, list]:
    """Vertices and triangle indices of a closed vertical prism over a convex
    ``polygon`` [(x, y), ...] (counter-clockwise) from height ``z0`` to ``z1``."""
    n = len(polygon)
    verts = [[x, y, z] for z in (z0, z1) for x, y in polygon]
    idx: list[int] = []
    for k in range(n):
        a, b = k, (k + 1) % n
        idx += [a, b, n + b, a, n + b, n + a]
    for k in range(1, n - 1):
        idx += [0, k + 1, k, n, n + k, n + k + 1]
    return verts, idx


def box_polygon(hx: float, hy: float) -> list[tuple[float, float]]:
    return [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)]


def circle_polygon(radius: float, sides: int = 24, cx: float = 0.0, cy: float = 0.0) -> list[tuple[float, float]]:
    """A polygon whose edges touch the circle (so face-on distances are exact)."""
    r = radius / math.cos(math.pi / sides)
    return [(cx + r * math.cos(2 * math.pi * (k + 0.5) / sides), cy + r * math.sin(2 * math.pi * (k + 0.5) / sides))
            for k in range(sides)]


def trimesh_shape(cid: int, parts: list[tuple[list, list]]) -> int:
    """A static triangle-mesh collision shape made of (vertices, indices) parts.

    Rays against triangle meshes cost a third of rays against Bullet's convex
    boxes and cylinders (which go through GJK), which is what makes the
    lasers cheap; the world never runs the dynamics, so static meshes are
    moved with ``resetBasePositionAndOrientation``."""
    p = pybullet()
    verts: list = []
    idx: list[int] = []
    for v, i in parts:
        idx += [len(verts) + k for k in i]
        verts += v
    return p.createCollisionShape(p.GEOM_MESH, vertices=verts, indices=idx,
                                  flags=p.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=cid)
