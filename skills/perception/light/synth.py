"""Drawn signal towers and pasting towers onto other images.

:func:`draw_tower` paints a Festo-style tower (36 mm wide, three 34 mm
segments green-yellow-red from the bottom, each with a 5 mm unlit border,
a housing above) with a randomised look: lit segments bright and saturated,
often with an over-exposed core and a glow around them; unlit segments
dull translucent plastic of the same hue, from dark to fairly light;
shading across the cylinder; random housing colour.  Together with
rendered towers pasted onto procedural backgrounds this spans far more
looks than one renderer, which is what lets the models carry over to
camera images of real towers.

Boxes are (x, y, w, h) pixels of the tower outline (housing to bottom
segment); masks are float alpha in [0, 1].
"""
from __future__ import annotations

import cv2
import numpy as np

# hue (OpenCV 0..180) of each light: green, yellow, red
HUES = (60, 25, 0)
SEGMENT_MM, BORDER_MM, HOUSING_MM, WIDTH_MM = 34.0, 5.0, 45.0, 36.0


def _hsv_bgr(h: float, s: float, v: float) -> np.ndarray:
    hsv = np.uint8([[[int(h) % 180, int(np.clip(s, 0, 255)), int(np.clip(v, 0, 255))]]])
    return cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0].astype(np.float32)


def draw_tower(rng: np.random.Generator, width: int, state: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(BGR float image, alpha, glow alpha) of a tower ``width`` pixels wide,
    drawn at 4x and reduced.  The image's height is the tower's height."""
    up = 4
    wpx = max(3, int(width)) * up
    mm = wpx / WIDTH_MM
    seg, border, housing = SEGMENT_MM * mm, BORDER_MM * mm, HOUSING_MM * mm * rng.uniform(0.8, 1.15)
    hpx = int(round(3 * seg + housing))
    img = np.zeros((hpx, wpx, 3), np.float32)
    xs = (np.arange(wpx) + 0.5) / wpx * 2 - 1                          # -1..1 across the cylinder
    shade = np.sqrt(np.clip(1 - xs ** 2, 0, 1))                         # lambert-ish across the width
    light_side = rng.uniform(-0.6, 0.6)
    shade = (0.55 + 0.45 * shade) * (1 + light_side * xs * 0.5)
    housing_col = _hsv_bgr(rng.uniform(0, 180), rng.uniform(0, 40), rng.uniform(15, 120))
    border_col = _hsv_bgr(rng.uniform(0, 180), rng.uniform(0, 30), rng.uniform(20, 170))
    img[:int(housing)] = housing_col * shade[None, :, None]
    glow = np.zeros((hpx, wpx), np.float32)
    glow_cols = np.zeros((hpx, wpx, 3), np.float32)
    exposure = rng.uniform(0.85, 1.0)
    for i in range(3):                                                  # 0 green at the bottom
        top = int(round(hpx - (i + 1) * seg))
        bot = int(round(hpx - i * seg))
        img[top:bot] = border_col * shade[None, :, None]
        lt, lb = int(round(top + border / 2)), int(round(bot - border / 2))
        hue = HUES[i] + rng.uniform(-6, 6)
        if (state >> i) & 1:
            col = _hsv_bgr(hue, rng.uniform(170, 255), 255 * exposure)
            core = rng.uniform(0.0, 0.9)                                # over-exposure: white centre
            prof = np.clip(1.2 * shade, 0, 1.15)
            seg_img = col[None, None, :] * prof[None, :, None]
            white = core * np.exp(-(xs / rng.uniform(0.3, 0.8)) ** 2)
            seg_img = seg_img * (1 - white[None, :, None]) + 255.0 * white[None, :, None]
            img[lt:lb] = seg_img
            glow[lt:lb] = 1.0
            glow_cols[lt:lb] = col
        else:
            col = _hsv_bgr(hue, rng.uniform(40, 200), rng.uniform(30, 140))
            spec = rng.uniform(0, 0.35) * np.exp(-((xs - rng.uniform(-0.5, 0.5)) / 0.15) ** 2)
            img[lt:lb] = col[None, None, :] * shade[None, :, None] + 255.0 * spec[None, :, None]
    alpha = np.ones((hpx, wpx), np.float32)
    size = (max(3, int(width)), max(4, int(round(hpx / up))))
    img = cv2.resize(np.clip(img, 0, 255), size, interpolation=cv2.INTER_AREA)
    alpha = cv2.resize(alpha, size, interpolation=cv2.INTER_AREA)
    glow = cv2.resize(glow * rng.uniform(0.0, 1.0), size, interpolation=cv2.INTER_AREA)
    glow_cols = cv2.resize(glow_cols, size, interpolation=cv2.INTER_AREA)
    return img, alpha, np.dstack([glow, glow_cols])


def paste(dst: np.ndarray, img: np.ndarray, alpha: np.ndarray, x: int, y: int,
          glow: np.ndarray | None = None) -> tuple[int, int, int, int]:
    """Alpha-blend ``img`` into ``dst`` (uint8 BGR, in place) with its top-left
    at (x, y); a glow (alpha + colour planes) spills around lit parts.
    Returns the pasted box clipped to ``dst``."""
    h, w = alpha.shape
    H, W = dst.shape[:2]
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, W), min(y + h, H)
    if x1 <= x0 or y1 <= y0:
        return (x0, y0, 0, 0)
    region = dst[y0:y1, x0:x1].astype(np.float32)
    if glow is not None and glow[:, :, 0].max() > 0:
        pad = max(2, w // 2)
        g = cv2.copyMakeBorder(glow, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
        g = cv2.GaussianBlur(g, (0, 0), max(1.0, w / 3.0))
        gx0, gy0 = x - pad, y - pad
        bx0, by0 = max(gx0, 0), max(gy0, 0)
        bx1, by1 = min(gx0 + g.shape[1], W), min(gy0 + g.shape[0], H)
        sub = g[by0 - gy0:by1 - gy0, bx0 - gx0:bx1 - gx0]
        strength = np.clip(sub[:, :, :1] * 1.5, 0, 1)
        colour = sub[:, :, 1:] / np.maximum(sub[:, :, :1], 1e-3)
        area = dst[by0:by1, bx0:bx1].astype(np.float32)
        dst[by0:by1, bx0:bx1] = np.clip(area + strength * 0.6 * colour, 0, 255).astype(np.uint8)
        region = dst[y0:y1, x0:x1].astype(np.float32)
    a = alpha[y0 - y:y1 - y, x0 - x:x1 - x, None]
    src = img[y0 - y:y1 - y, x0 - x:x1 - x]
    dst[y0:y1, x0:x1] = np.clip(region * (1 - a) + src * a, 0, 255).astype(np.uint8)
    return (x0, y0, x1 - x0, y1 - y0)
