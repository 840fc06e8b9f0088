"""The hall around the field: walls, ceiling and floor for the camera.

A real camera never sees empty space behind a station: it sees the hall,
with windows, racks, doors, machines, signs, lamps and people's things.
:class:`Hall` puts visual-only textured quads (no collision: the lasers and
the oracle never see them) ``distance`` metres outside the floor: four walls
``height`` high, a ceiling with lamp strips and a hall floor under the
field's.  The textures are drawn procedurally from a seed (:func:`wall_texture`,
:func:`ceiling_texture`, :func:`floor_texture`), several per hall, and
:meth:`Hall.restyle` swaps them, so training views see many halls.

Field frame, metres.  Textures are BGR uint8 written as PNG into a cache
directory (TinyRenderer loads textures from files).
"""
from __future__ import annotations

import os
import tempfile

import cv2
import numpy as np

from rll_bt.rules import Rect

from .bullet import pybullet

HALL_DISTANCE = 2.5        # walls this far outside the floor, metres
HALL_HEIGHT = 5.0
STYLES = 3                 # textures of each kind per hall


def _col(rng, lo=0, hi=256):
    return tuple(int(c) for c in rng.integers(lo, hi, 3))


def _grey(rng, lo, hi, tint=12):
    g = int(rng.integers(lo, hi))
    return tuple(int(np.clip(g + rng.integers(-tint, tint + 1), 0, 255)) for _ in range(3))


def _noise(rng, h, w, cells=8, amp=18.0) -> np.ndarray:
    small = rng.normal(0.0, 1.0, (max(2, cells * h // w), cells)).astype(np.float32)
    big = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    fine = rng.normal(0.0, 0.35, (h, w)).astype(np.float32)
    return (big + fine)[:, :, None] * amp


def wall_texture(rng: np.random.Generator, w: int = 1024, h: int = 320) -> np.ndarray:
    """A hall wall, floor at the bottom edge: painted wall and a darker
    base, windows, racks, doors, machines, pipes, signs and posters."""
    img = np.empty((h, w, 3), np.float32)
    top, bot = np.array(_grey(rng, 120, 235), np.float32), np.array(_grey(rng, 90, 200), np.float32)
    t = np.linspace(0, 1, h, dtype=np.float32)[:, None, None]
    img[:] = top * (1 - t) + bot * t
    img += _noise(rng, h, w, int(rng.integers(4, 16)), float(rng.uniform(4, 20)))
    base = int(h * rng.uniform(0.78, 0.9))
    img[base:] = np.array(_grey(rng, 40, 140), np.float32) + _noise(rng, h - base, w, 16, 8.0)
    img = np.clip(img, 0, 255).astype(np.uint8)
    if rng.random() < 0.7:                                          # a row of windows
        wy0, wy1 = int(h * rng.uniform(0.05, 0.2)), int(h * rng.uniform(0.3, 0.55))
        ww, gap = int(rng.integers(40, 140)), int(rng.integers(10, 80))
        sky = _col(rng, 150, 256)
        for x in range(int(rng.integers(0, 60)), w, ww + gap):
            cv2.rectangle(img, (x, wy0), (x + ww, wy1), sky, -1)
            for k in range(1, int(rng.integers(1, 4))):
                xx = x + k * ww // 3
                cv2.line(img, (xx, wy0), (xx, wy1), _grey(rng, 30, 120), 2)
            cv2.rectangle(img, (x, wy0), (x + ww, wy1), _grey(rng, 20, 110), 3)
    for _ in range(int(rng.integers(0, 4))):                        # pallet racks (coloured beams)
        x0 = int(rng.integers(0, w - 60))
        x1 = min(w - 1, x0 + int(rng.integers(80, 300)))
        upright, beam = _col(rng), _col(rng)
        y_top = int(h * rng.uniform(0.15, 0.5))
        for x in (x0, x1):
            cv2.rectangle(img, (x, y_top), (x + 5, base), upright, -1)
        for y in range(base - 4, y_top, -int(rng.integers(25, 60))):
            cv2.rectangle(img, (x0, y - 4), (x1 + 5, y), beam, -1)
            for _ in range(int(rng.integers(0, 5))):                # boxes on the shelf
                bx = int(rng.integers(x0 + 6, max(x0 + 7, x1 - 20)))
                bw, bh = int(rng.integers(8, 40)), int(rng.integers(6, 22))
                cv2.rectangle(img, (bx, y - 4 - bh), (bx + bw, y - 4), _col(rng, 60, 230), -1)
    for _ in range(int(rng.integers(0, 3))):                        # doors
        dw, dh = int(rng.integers(40, 110)), int(h * rng.uniform(0.35, 0.6))
        x = int(rng.integers(0, w - dw))
        cv2.rectangle(img, (x, base - dh), (x + dw, base), _col(rng, 30, 220), -1)
        cv2.rectangle(img, (x, base - dh), (x + dw, base), _grey(rng, 20, 90), 2)
    for _ in range(int(rng.integers(0, 5))):                        # machines, cabinets, tables
        mw, mh = int(rng.integers(20, 160)), int(rng.integers(15, 110))
        x = int(rng.integers(0, w - mw))
        c = _grey(rng, 50, 220) if rng.random() < 0.7 else _col(rng, 40, 230)
        cv2.rectangle(img, (x, base - mh), (x + mw, base + int(rng.integers(0, 12))), c, -1)
        if rng.random() < 0.5:
            px, py = x + int(rng.integers(2, max(3, mw - 12))), base - mh + int(rng.integers(2, max(3, mh - 10)))
            cv2.rectangle(img, (px, py), (px + int(rng.integers(4, 14)), py + int(rng.integers(4, 12))),
                          _col(rng), -1)
    for _ in range(int(rng.integers(0, 4))):                        # pipes and cable trays
        y = int(rng.integers(5, base))
        cv2.line(img, (0, y), (w, y + int(rng.integers(-5, 6))), _grey(rng, 40, 230), int(rng.integers(2, 8)))
    for _ in range(int(rng.integers(2, 12))):                       # signs, posters, extinguishers, lamps
        x, y = int(rng.integers(0, w - 10)), int(rng.integers(5, base - 10))
        kind = int(rng.integers(0, 5))
        if kind == 0:                                               # poster
            cv2.rectangle(img, (x, y), (x + int(rng.integers(10, 50)), y + int(rng.integers(12, 60))),
                          _col(rng), -1)
        elif kind == 1:                                             # exit sign (green) or warning (yellow)
            c = (60, 170, 30) if rng.random() < 0.5 else (20, 200, 230)
            cv2.rectangle(img, (x, y), (x + int(rng.integers(12, 30)), y + int(rng.integers(6, 14))), c, -1)
        elif kind == 2:                                             # fire extinguisher: a red upright
            ew = int(rng.integers(4, 10))
            cv2.rectangle(img, (x, y), (x + ew, y + int(ew * rng.uniform(2.5, 4))), (30, 30, 200), -1)
        elif kind == 3:                                             # hazard stripes
            sw = int(rng.integers(20, 120))
            for k in range(0, sw, 8):
                cv2.line(img, (x + k, y), (x + k + 6, y + 8), (0, 210, 240) if k % 16 else (20, 20, 20), 4)
        else:                                                       # a wall lamp
            cv2.ellipse(img, (x, y), (int(rng.integers(3, 14)), int(rng.integers(2, 8))), 0, 0, 360,
                        _col(rng, 200, 256), -1)
    if rng.random() < 0.5:
        img = cv2.GaussianBlur(img, (3, 3), 0)
    return img


def ceiling_texture(rng: np.random.Generator, w: int = 512, h: int = 512) -> np.ndarray:
    """A ceiling: dark to mid grey with beams and rows of bright lamp strips."""
    img = np.clip(np.array(_grey(rng, 30, 150), np.float32) + _noise(rng, h, w, 8, 10.0), 0, 255).astype(np.uint8)
    for y in range(int(rng.integers(0, 40)), h, int(rng.integers(30, 90))):
        cv2.line(img, (0, y), (w, y), _grey(rng, 20, 120), int(rng.integers(2, 8)))
    lamp = _col(rng, 220, 256)
    step_x, step_y = int(rng.integers(60, 160)), int(rng.integers(60, 160))
    for x in range(int(rng.integers(0, 50)), w, step_x):
        for y in range(int(rng.integers(0, 50)), h, step_y):
            cv2.rectangle(img, (x, y), (x + int(rng.integers(8, 20)), y + int(rng.integers(30, 60))), lamp, -1)
    return img


def floor_texture(rng: np.random.Generator, w: int = 1024, h: int = 1024) -> np.ndarray:
    """A hall floor: concrete or coated grey with tape lines and marks."""
    img = np.clip(np.array(_grey(rng, 70, 190, 20), np.float32) + _noise(rng, h, w, 32, 14.0), 0, 255).astype(np.uint8)
    for _ in range(int(rng.integers(2, 10))):
        c = (0, 200, 230) if rng.random() < 0.5 else _grey(rng, 200, 256, 5)
        if rng.random() < 0.5:
            x = int(rng.integers(0, w))
            cv2.line(img, (x, 0), (x, h), c, int(rng.integers(2, 6)))
        else:
            y = int(rng.integers(0, h))
            cv2.line(img, (0, y), (w, y), c, int(rng.integers(2, 6)))
    for _ in range(int(rng.integers(0, 20))):                       # stains and marks
        cv2.circle(img, (int(rng.integers(0, w)), int(rng.integers(0, h))), int(rng.integers(3, 40)),
                   _grey(rng, 40, 200), -1)
    return cv2.GaussianBlur(img, (3, 3), 0)


def _texture_file(kind: str, seed: int, style: int, directory: str | None) -> str:
    directory = directory or os.path.join(tempfile.gettempdir(), "rll_bt_sim_hall")
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"{kind}_{seed}_{style}.png")
    if not os.path.exists(path):
        rng = np.random.default_rng([seed, style, {"wall": 0, "ceiling": 1, "floor": 2}[kind]])
        img = {"wall": wall_texture, "ceiling": ceiling_texture, "floor": floor_texture}[kind](rng)
        fd, tmp = tempfile.mkstemp(suffix=".png", dir=directory)
        os.close(fd)
        if not cv2.imwrite(tmp, img):
            os.unlink(tmp)
            raise OSError(f"cannot write hall texture {tmp}")
        os.replace(tmp, path)      # atomic: parallel workers may race here
    return path


def _quad(cid: int, corners, uv_scale=(1.0, 1.0)) -> int:
    """A visual-only quad body with corners (bottom-left, bottom-right,
    top-right, top-left) seen from the side they wind counter-clockwise on."""
    p = pybullet()
    c = np.asarray(corners, float)
    centre = c.mean(axis=0)
    v = (c - centre).tolist()
    n = np.cross(c[1] - c[0], c[3] - c[0])
    n = (n / np.linalg.norm(n)).tolist()
    su, sv = uv_scale
    vis = p.createVisualShape(p.GEOM_MESH, vertices=v, indices=[0, 1, 2, 0, 2, 3],
                              uvs=[(0.0, 0.0), (su, 0.0), (su, sv), (0.0, sv)], normals=[n] * 4,
                              rgbaColor=[1, 1, 1, 1], physicsClientId=cid)
    return p.createMultiBody(0, -1, vis, basePosition=centre.tolist(), physicsClientId=cid)


class Hall:
    """Walls, ceiling and floor around ``floor`` (a :class:`Rect`), textured
    from ``seed`` (see the module)."""

    def __init__(self, cid: int, floor: Rect, seed: int, texture_dir: str | None = None,
                 distance: float = HALL_DISTANCE, height: float = HALL_HEIGHT):
        self.cid = cid
        p = pybullet()
        x0, y0 = floor.x_min - distance, floor.y_min - distance
        x1, y1 = floor.x_max + distance, floor.y_max + distance
        z = height
        # each wall quad faces the field: (bottom-left, bottom-right, top-right, top-left) seen from inside
        self.walls = [_quad(cid, q) for q in (
            [(x0, y1, 0), (x1, y1, 0), (x1, y1, z), (x0, y1, z)],      # far (+y) wall
            [(x1, y0, 0), (x0, y0, 0), (x0, y0, z), (x1, y0, z)],      # near (-y) wall
            [(x0, y0, 0), (x0, y1, 0), (x0, y1, z), (x0, y0, z)],      # -x wall
            [(x1, y1, 0), (x1, y0, 0), (x1, y0, z), (x1, y1, z)])]     # +x wall
        self.ceiling = _quad(cid, [(x0, y1, z), (x1, y1, z), (x1, y0, z), (x0, y0, z)])
        self.floor = _quad(cid, [(x0, y0, -0.012), (x1, y0, -0.012), (x1, y1, -0.012), (x0, y1, -0.012)])
        self.bodies = [*self.walls, self.ceiling, self.floor]
        def load(kind, k):
            return p.loadTexture(_texture_file(kind, seed, k, texture_dir), physicsClientId=cid)
        self._textures = {kind: [load(kind, k) for k in range(STYLES)] for kind in ("wall", "ceiling", "floor")}
        self.restyle(np.random.default_rng(seed))

    def restyle(self, rng: np.random.Generator) -> None:
        """Give walls, ceiling and floor textures drawn at random from the hall's styles."""
        p = pybullet()
        tex = self._textures
        for body in self.walls:
            p.changeVisualShape(body, -1, textureUniqueId=tex["wall"][int(rng.integers(STYLES))],
                                physicsClientId=self.cid)
        p.changeVisualShape(self.ceiling, -1, textureUniqueId=tex["ceiling"][int(rng.integers(STYLES))],
                            physicsClientId=self.cid)
        p.changeVisualShape(self.floor, -1, textureUniqueId=tex["floor"][int(rng.integers(STYLES))],
                            physicsClientId=self.cid)
