"""Procedural backgrounds: textures and clutter no renderer made.

Training pastes towers onto these (and uses them tower-free as negatives) so
that the detector and the network learn the tower, not the look of the
simulator's scenes.  Everything is drawn from ``rng``: multi-scale noise,
gradients, stripes and tiles, then clutter (bars, boxes, discs, lines,
coloured lamps and reflections, dark upright bars shaped like a tower's
silhouette), then blur.  Images are BGR uint8.
"""
from __future__ import annotations

import cv2
import numpy as np


def _colour(rng: np.random.Generator, lo: int = 0, hi: int = 256) -> tuple[int, int, int]:
    return tuple(int(c) for c in rng.integers(lo, hi, 3))


def _noise(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """Multi-octave value noise, float in [0, 1], 3 channels."""
    out = np.zeros((h, w, 3), np.float32)
    amp_sum = 0.0
    for octave in range(int(rng.integers(2, 5))):
        cells = int(rng.integers(2, 6)) * 2 ** octave
        small = rng.random((max(2, cells * h // w), max(2, cells), 3)).astype(np.float32)
        amp = 0.6 ** octave
        out += amp * cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
        amp_sum += amp
    return np.clip(out / amp_sum, 0, 1)


def _base(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    kind = int(rng.integers(0, 5))
    c0 = np.array(_colour(rng), np.float32)
    c1 = np.array(_colour(rng), np.float32)
    if kind == 0:                                    # smooth noise between two colours
        t = _noise(rng, h, w)[:, :, :1]
        img = c0 * (1 - t) + c1 * t
    elif kind == 1:                                  # linear gradient
        ang = rng.uniform(0, np.pi)
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        t = (np.cos(ang) * xx + np.sin(ang) * yy)
        t = ((t - t.min()) / max(float(np.ptp(t)), 1.0))[:, :, None]
        img = c0 * (1 - t) + c1 * t
    elif kind == 2:                                  # stripes (shelves, blinds, grids)
        period = int(rng.integers(6, 60))
        yy, xx = np.mgrid[0:h, 0:w]
        axis = xx if rng.random() < 0.5 else yy
        t = ((axis // max(1, period // 2)) % 2).astype(np.float32)[:, :, None]
        img = c0 * (1 - t) + c1 * t
    elif kind == 3:                                  # tiles / checkerboard
        s = int(rng.integers(8, 80))
        yy, xx = np.mgrid[0:h, 0:w]
        t = (((xx // s) + (yy // s)) % 2).astype(np.float32)[:, :, None]
        img = c0 * (1 - t) + c1 * t
    else:                                            # coloured noise (carpet, concrete)
        img = _noise(rng, h, w) * 255.0
    img = img + rng.normal(0, rng.uniform(0, 12), (h, w, 1)).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def _clutter(rng: np.random.Generator, img: np.ndarray, count: int) -> None:
    h, w = img.shape[:2]
    for _ in range(count):
        kind = int(rng.integers(0, 8))
        x, y = int(rng.integers(-20, w)), int(rng.integers(-20, h))
        col = _colour(rng)
        if kind == 0:                                # box
            cv2.rectangle(img, (x, y), (x + int(rng.integers(5, w // 2)), y + int(rng.integers(5, h // 2))),
                          col, -1 if rng.random() < 0.7 else int(rng.integers(1, 4)))
        elif kind == 1:                              # line / cable / edge
            cv2.line(img, (x, y), (int(rng.integers(0, w)), int(rng.integers(0, h))), col,
                     int(rng.integers(1, 6)), cv2.LINE_AA)
        elif kind == 2:                              # disc / blob
            cv2.circle(img, (x, y), int(rng.integers(3, 60)), col, -1, cv2.LINE_AA)
        elif kind == 3:                              # upright dark bar about a tower's shape
            bw = int(rng.integers(4, 40))
            bh = int(bw * rng.uniform(2.0, 6.0))
            cv2.rectangle(img, (x, y), (x + bw, y + bh), _colour(rng, 0, 90), -1)
        elif kind == 4:                              # lamp, LED or reflection in a saturated colour
            hue = int(rng.choice([0, 15, 30, 60, 90, 120, 150, 175]))
            hsv = np.uint8([[[hue, int(rng.integers(150, 256)), int(rng.integers(150, 256))]]])
            bgr = tuple(int(c) for c in cv2.cvtColor(hsv, cv2.COLOR_HSV2BGR)[0, 0])
            cv2.ellipse(img, (x, y), (int(rng.integers(2, 25)), int(rng.integers(2, 25))), 0, 0, 360, bgr, -1)
        elif kind == 5:                              # polygon
            pts = np.stack([rng.integers(0, w, 4), rng.integers(0, h, 4)], axis=1).astype(np.int32)
            cv2.fillPoly(img, [pts], col)
        elif kind == 6:                              # text-like marks (labels, posters)
            cv2.putText(img, "".join(chr(int(c)) for c in rng.integers(65, 91, int(rng.integers(2, 8)))),
                        (x, y), int(rng.integers(0, 8)), rng.uniform(0.4, 2.0), col, int(rng.integers(1, 3)))
        else:                                        # a pole or table leg: a long thin upright
            bw = int(rng.integers(2, 12))
            cv2.rectangle(img, (x, y), (x + bw, y + int(rng.integers(h // 4, h))), col, -1)


def procedural_background(rng: np.random.Generator, h: int = 480, w: int = 640,
                          clutter: tuple[int, int] = (4, 40)) -> np.ndarray:
    """A random tower-free BGR image of ``h`` x ``w`` pixels."""
    img = cv2.resize(_base(rng, (h + 1) // 2, (w + 1) // 2), (w, h), interpolation=cv2.INTER_NEAREST)
    _clutter(rng, img, int(rng.integers(*clutter)))
    if rng.random() < 0.7:                           # halls are mostly grey: take colour out
        grey = cv2.cvtColor(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
        keep = rng.uniform(0.0, 0.6)
        img = cv2.addWeighted(img, keep, grey, 1.0 - keep, 0.0)
        _clutter(rng, img, int(rng.integers(0, 6)))  # a few coloured things stay
    if rng.random() < 0.5:
        k = int(rng.choice([3, 5]))
        img = cv2.GaussianBlur(img, (k, k), 0)
    return img
