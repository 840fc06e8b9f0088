"""Frames of the evaluation renderers: towers on real photographs, through a camera.

:func:`frame` lays 0-3 towers of one renderer (:data:`RENDERERS`: ``raycast``,
renderer B, or ``sketch``, renderer C), each 40-200 pixels high and whole
inside the frame, onto a crop of a photograph, then puts the frame through
that renderer's camera:

- ``raycast``: composed in linear light (the photograph linearised, the
  towers' HDR colour and the glow of lit lenses added), optical blur
  (Gaussian, sigma 0-2 px) before the sensor, exposure 0.5-1.6, clipping
  with the overflow of a saturated channel bled into the others, sRGB
  gamma, sensor noise, JPEG quality 45-95;
- ``sketch``: composed on 8-bit values (its own glow), exposure 0.5-1.6 as
  a gain on the 8-bit values, defocus (a disc of radius 0-2 px) or
  Gaussian blur after it, shot noise, JPEG 45-95 with 4:2:0 chroma.

Labels are :class:`..dataset.Truth` with the box the renderer reports and a
tag-like search region (the box widened by 1.5 widths to each side and half
its height above and below, the expected height off by about 3 %), as a
tag would give (:func:`..region.tower_region`).
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from ..dataset import PackedFrame, Truth
from ..photos import photo_backdrop
from . import raycast, sketch

RENDERERS = ("raycast", "sketch")
SIZES = ((640, 480), (512, 384), (480, 360), (400, 300), (320, 240))
HEIGHTS = (40.0, 200.0)
EXPOSURE = (0.5, 1.6)
BLUR = 2.0
JPEG = (45, 95)


def _linear(img8: np.ndarray) -> np.ndarray:
    c = img8.astype(np.float32) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def _srgb8(lin: np.ndarray) -> np.ndarray:
    c = np.clip(lin, 0, 1)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.clip(s * 255.0 + 0.5, 0, 255).astype(np.uint8)


def _place(rng: np.random.Generator, size, boxes, w: int, h: int, margin: int = 4):
    """A top-left corner for a w x h box inside the frame, clear of ``boxes``, or None."""
    fw, fh = size
    if w + 2 * margin >= fw or h + 2 * margin >= fh:
        return None
    for _ in range(30):
        x, y = int(rng.integers(margin, fw - w - margin)), int(rng.integers(margin, fh - h - margin))
        if all(x + w + 6 < bx or bx + bw + 6 < x or y + h + 6 < by or by + bh + 6 < y
               for bx, by, bw, bh in boxes):
            return x, y
    return None


def _region(rng: np.random.Generator, box, size) -> tuple[tuple[int, int, int, int], float]:
    x, y, w, h = box
    fw, fh = size
    rx0, ry0 = max(0, int(math.floor(x - 1.5 * w))), max(0, int(math.floor(y - 0.5 * h)))
    rx1, ry1 = min(fw, int(math.ceil(x + 2.5 * w))), min(fh, int(math.ceil(y + 1.5 * h)))
    return (rx0, ry0, rx1 - rx0, ry1 - ry0), float(h * (1 + rng.normal(0, 0.03)))


def _truth(rng, box, state, size) -> Truth:
    b = tuple(int(round(v)) for v in box)
    region, height = _region(rng, box, size)
    return Truth(b, int(state), True, region, height, b)


def frame(rng: np.random.Generator, renderer: str, towers: int, photos: str = "heldout",
          size: tuple[int, int] | None = None) -> tuple[np.ndarray, list[Truth]]:
    """One BGR frame with ``towers`` towers of ``renderer`` on a photograph of ``photos``."""
    if renderer not in RENDERERS:
        raise ValueError(f"renderer must be one of {', '.join(RENDERERS)}, not {renderer!r}")
    size = size or SIZES[int(rng.integers(len(SIZES)))]
    fw, fh = size
    back = photo_backdrop(rng, fh, fw, photos)
    if back is None:
        raise RuntimeError("the evaluation renderers need photographs (pip install scikit-image)")
    if renderer == "raycast":
        return _raycast_frame(rng, back, towers, size)
    return _sketch_frame(rng, back, towers, size)


def _heights(rng: np.random.Generator, n: int, fh: int) -> list[float]:
    hi = min(HEIGHTS[1], 0.85 * fh)
    return [float(np.exp(rng.uniform(math.log(HEIGHTS[0]), math.log(hi)))) for _ in range(n)]


def _raycast_frame(rng, back8, n, size):
    fw, fh = size
    lin = _linear(back8[:, :, ::-1])                              # RGB linear
    glow = np.zeros_like(lin)
    truths, boxes = [], []
    for height in _heights(rng, n, fh):
        state = int(rng.integers(0, 8))
        tower = raycast.random_tower(rng, state)
        patch = raycast.render_tower(rng, tower, raycast.random_light(rng, lin), height)
        bx, by, bw, bh = patch.box
        ph, pw = patch.alpha.shape
        at = _place(rng, size, boxes, int(math.ceil(bw)), int(math.ceil(bh)))
        if at is None or bh <= 0:
            continue
        ox, oy = int(round(at[0] - bx)), int(round(at[1] - by))
        x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + pw, fw), min(oy + ph, fh)
        a = patch.alpha[y0 - oy:y1 - oy, x0 - ox:x1 - ox, None]
        lin[y0:y1, x0:x1] = lin[y0:y1, x0:x1] * (1 - a) + patch.colour[y0 - oy:y1 - oy, x0 - ox:x1 - ox]
        glow[y0:y1, x0:x1] += patch.emission[y0 - oy:y1 - oy, x0 - ox:x1 - ox]
        box = (ox + bx, oy + by, bw, bh)
        boxes.append(box)
        truths.append((box, state, bw))
    if truths:
        width = float(np.mean([t[2] for t in truths]))
        halo = cv2.GaussianBlur(glow, (0, 0), rng.uniform(1.0, 3.0))
        veil = cv2.GaussianBlur(glow, (0, 0), max(1.0, width * rng.uniform(0.3, 1.2)))
        lin += rng.uniform(0, 0.5) * halo + rng.uniform(0, 0.4) * veil
    sigma = rng.uniform(0, BLUR)
    if sigma > 0.3:
        lin = cv2.GaussianBlur(lin, (0, 0), sigma)
    lin *= rng.uniform(*EXPOSURE)
    over = np.clip(lin.max(axis=2, keepdims=True) - 1.0, 0, None)
    lin = lin + 0.5 * over                                       # a saturated channel bleeds into the others
    img = _srgb8(lin)[:, :, ::-1]
    noise = rng.normal(0, rng.uniform(0.5, 4.0), img.shape)
    img = np.clip(img + noise, 0, 255).astype(np.uint8)
    img = _jpeg(img, int(rng.integers(JPEG[0], JPEG[1] + 1)))
    return img, [_truth(rng, b, s, size) for b, s, _ in truths]


def _sketch_frame(rng, back8, n, size):
    fw, fh = size
    img = back8.astype(np.float32)
    truths, boxes = [], []
    for height in _heights(rng, n, fh):
        state = int(rng.integers(0, 8))
        spr = sketch.draw(rng, state, height)
        at = _place(rng, size, boxes, int(math.ceil(spr.box[2])), int(math.ceil(spr.box[3])))
        if at is None:
            continue
        ox, oy = int(round(at[0] - spr.box[0])), int(round(at[1] - spr.box[1]))
        sketch.stamp(img, spr, ox, oy)
        box = (ox + spr.box[0], oy + spr.box[1], spr.box[2], spr.box[3])
        boxes.append(box)
        truths.append((box, state))
    img *= rng.uniform(*EXPOSURE)
    img = np.clip(img, 0, 255)
    r = rng.uniform(0, BLUR)
    if r > 0.3:
        if rng.random() < 0.5:
            k = int(math.ceil(r)) * 2 + 1
            disc = np.zeros((k, k), np.float32)
            cv2.circle(disc, (k // 2, k // 2), int(round(r)), 1.0, -1)
            img = cv2.filter2D(img, -1, disc / disc.sum())
        else:
            img = cv2.GaussianBlur(img, (0, 0), r)
    scale = rng.uniform(0.2, 1.5)                                 # shot noise: grows with the signal
    img = img + rng.normal(0, 1, img.shape) * np.sqrt(np.maximum(img, 1.0)) * scale * 0.25
    img = np.clip(img + 0.5, 0, 255).astype(np.uint8)
    img = _jpeg(img, int(rng.integers(JPEG[0], JPEG[1] + 1)), subsample=True)
    return img, [_truth(rng, b, s, size) for b, s in truths]


def _jpeg(img: np.ndarray, quality: int, subsample: bool = False) -> np.ndarray:
    params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)]
    if subsample and hasattr(cv2, "IMWRITE_JPEG_SAMPLING_FACTOR"):
        params += [cv2.IMWRITE_JPEG_SAMPLING_FACTOR, cv2.IMWRITE_JPEG_SAMPLING_FACTOR_420]
    ok, buf = cv2.imencode(".jpg", img, params)
    return cv2.imdecode(buf, cv2.IMREAD_COLOR) if ok else img


def made(renderer: str, seed: int, towers: int, free: int, photos: str = "heldout") -> list:
    """``towers`` frames with 1-3 towers and ``free`` tower-free ones, seeded: [(BGR image, [Truth])]."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(towers + free):
        n = int(rng.choice([1, 1, 1, 2, 3])) if i < towers else 0
        img, truths = frame(rng, renderer, n, photos)
        if n and not truths:
            continue
        out.append((img, truths))
    return out


def frames(renderer: str, seed: int, towers: int, free: int, photos: str = "heldout") -> list[PackedFrame]:
    """:func:`made`, packed as the project's labelled frames."""
    return [PackedFrame.pack(img, truths, renderer if truths else f"free-{renderer}")
            for img, truths in made(renderer, seed, towers, free, photos)]


def raycast_frames(seed: int, towers: int, free: int, photos: str = "train") -> list:
    """Renderer B's frames as a training source (``ChunkSpec.source``): the
    benchmark's reverse experiment, training on B and testing on the project's renderer."""
    return made("raycast", seed, towers, free, photos)
