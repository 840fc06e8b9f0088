"""A colour-threshold light reader in the style of the Carologistics colour
model (the baseline the paper compares its HOG + network chain against).

The tower's region of interest comes from geometry (there: laser and
machine type; here: the tag pose, :func:`.region.tower_region` with no
margin); inside it the three light segments are fixed fractions of the
height (red on top).  Each pixel is classified in YUV: *lit* in a light's
colour when its luma is at least that light's ``min_luma``, its chroma (the
distance of U, V from grey) at least ``min_chroma`` and its chroma
direction within ``max_angle`` degrees of the light's reference colour.  A
light is on when at least ``min_fraction`` of its segment's pixels are lit.

Without a region it can only look for lit colour blobs (:meth:`find`):
upright blobs of one light's colour of plausible size count as a tower, so
a tower with every light off is never found, and coloured clutter is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .reader import overlap_of_smaller
from .synth import BORDER_MM, HOUSING_MM, SEGMENT_MM

LIGHT_ORDER = ("green", "yellow", "red")       # bits 0, 1, 2; bottom to top


@dataclass(frozen=True)
class ColourClass:
    bgr: tuple[int, int, int]       # reference colour of the lit light
    min_luma: float
    min_chroma: float = 30.0
    max_angle: float = 35.0         # degrees around the reference chroma direction

    @property
    def direction(self) -> float:
        y, u, v = cv2.cvtColor(np.uint8([[self.bgr]]), cv2.COLOR_BGR2YUV)[0, 0].astype(float)
        return math.degrees(math.atan2(v - 128.0, u - 128.0))


@dataclass(frozen=True)
class ColourModel:
    green: ColourClass = ColourClass((40, 230, 40), 80.0)
    yellow: ColourClass = ColourClass((20, 210, 240), 110.0)
    red: ColourClass = ColourClass((40, 40, 230), 60.0)
    min_fraction: float = 0.3

    def scaled(self, luma: float, fraction: float) -> ColourModel:
        """The model with every ``min_luma`` times ``luma`` and ``min_fraction`` set."""
        return ColourModel(*(replace(getattr(self, n), min_luma=getattr(self, n).min_luma * luma)
                             for n in LIGHT_ORDER), min_fraction=fraction)

    def lit(self, bgr: np.ndarray, light: str) -> np.ndarray:
        """Bool mask of the pixels lit in ``light``'s colour."""
        cls: ColourClass = getattr(self, light)
        yuv = cv2.cvtColor(bgr, cv2.COLOR_BGR2YUV).astype(np.float32)
        du, dv = yuv[..., 1] - 128.0, yuv[..., 2] - 128.0
        chroma = np.hypot(du, dv)
        angle = np.degrees(np.arctan2(dv, du))
        diff = np.abs((angle - cls.direction + 180.0) % 360.0 - 180.0)
        return (yuv[..., 0] >= cls.min_luma) & (chroma >= cls.min_chroma) & (diff <= cls.max_angle)

    def read(self, image: np.ndarray, box) -> int:
        """The light state (green 1, yellow 2, red 4) of the tower in ``box`` (x, y, w, h)."""
        x, y, w, h = (int(round(v)) for v in box)
        x0, y0 = max(0, x), max(0, y)
        x1, y1 = min(image.shape[1], x + w), min(image.shape[0], y + h)
        if x1 - x0 < 1 or y1 - y0 < 3:
            return 0
        roi = image[y0:y1, x0:x1]
        total = 3 * SEGMENT_MM + HOUSING_MM
        state = 0
        for i, light in enumerate(LIGHT_ORDER):                 # green at the bottom
            top = (HOUSING_MM + (2 - i) * SEGMENT_MM + BORDER_MM / 2) / total
            bot = (HOUSING_MM + (3 - i) * SEGMENT_MM - BORDER_MM / 2) / total
            a, b = int(round(y + top * h)) - y0, int(round(y + bot * h)) - y0
            seg = roi[max(0, a):max(max(0, a) + 1, min(roi.shape[0], b))]
            if seg.size and self.lit(seg, light).mean() >= self.min_fraction:
                state |= 1 << i
        return state

    def find(self, image: np.ndarray, min_height: int = 6) -> list[tuple[tuple[int, int, int, int], int]]:
        """Towers found by colour alone: (box, state) per upright lit blob."""
        found = []
        for i, light in enumerate(LIGHT_ORDER):
            mask = self.lit(image, light).astype(np.uint8)
            n, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
            for k in range(1, n):
                x, y, w, h, area = stats[k]
                if h < min_height or not (0.4 <= w / h <= 1.7) or area < 0.5 * w * h:
                    continue
                # the segment is a third of the lights: extend to the whole tower
                total = 3 * SEGMENT_MM + HOUSING_MM
                th = h * total / SEGMENT_MM
                ty = y - (HOUSING_MM + (2 - i) * SEGMENT_MM) / total * th
                box = (int(x), int(round(ty)), int(w), int(round(th)))
                found.append((box, self.read(image, box)))
        out = []
        for box, state in found:                               # merge segments of one tower
            if all(overlap_of_smaller(box, b) < 0.3 for b, _ in out):
                out.append((box, state))
        return out
