"""Renderer C: signal towers drawn flat, as an illustrator would, for evaluation only.

Deliberately unlike renderer B (:mod:`.raycast`), the PyBullet scenes and
the towers training draws: no light model and no 3-D geometry, but a
vector drawing in 8-bit colour, made at four times the size and reduced:

- lenses are rounded rectangles (corner radius up to a third of the
  width) with horizontal bands (a ribbed lens seen from the side) and a
  vertical gradient; unlit ones dark tinted, clear grey or milky white
  with a narrow highlight; lit ones a palette colour with a white-hot
  stripe down the middle and an outer glow of stacked, growing, fading
  copies (the "outer glow" of drawing programs), which also tints the
  lens's neighbours;
- between lenses either a gap, a thin dark line or a chrome band; a
  housing that may be short or taller than a lens, black, grey, white or
  a chrome gradient, with a flat, rounded or stepped top; a pole, a
  bracket plate or nothing below; at times a dark outline round it all;
- the drawing is then turned by up to 10 degrees, sheared by up to 0.12
  and squashed or stretched across by up to 20 % (its "perspective").

The truth box is the transformed silhouette of housing and lenses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

UP = 4
#: BGR palettes of lit lenses: green, yellow, red
LIT = (((40, 200, 30), (90, 230, 60), (80, 255, 170), (30, 160, 20)),
       ((0, 190, 255), (30, 230, 255), (0, 150, 250), (80, 240, 250)),
       ((20, 20, 220), (40, 40, 255), (60, 0, 200), (10, 60, 240)))
#: hue-ish tint of unlit lenses (BGR multipliers)
TINT = ((0.55, 1.0, 0.5), (0.45, 0.9, 1.0), (0.5, 0.5, 1.0))


@dataclass
class Sprite:
    colour: np.ndarray         # h x w x 3 float32, BGR 0..255
    alpha: np.ndarray          # h x w float32
    glow: np.ndarray           # h x w x 3 float32, added (screen) around lit lenses
    box: tuple[float, float, float, float]


def _rounded(img, x0, y0, x1, y1, r, colour):
    r = int(max(0, min(r, (x1 - x0) // 2, (y1 - y0) // 2)))
    cv2.rectangle(img, (x0 + r, y0), (x1 - r, y1), colour, -1)
    cv2.rectangle(img, (x0, y0 + r), (x1, y1 - r), colour, -1)
    for cx, cy in ((x0 + r, y0 + r), (x1 - r, y0 + r), (x0 + r, y1 - r), (x1 - r, y1 - r)):
        cv2.circle(img, (cx, cy), r, colour, -1)


def draw(rng: np.random.Generator, state: int, height_px: float) -> Sprite:
    """A tower whose truth box is about ``height_px`` high."""
    lens_ratio = rng.uniform(0.7, 1.4)                     # lens height / width
    gap_kind = int(rng.integers(3))                        # 0 gap, 1 dark line, 2 chrome band
    gap = rng.uniform(0.02, 0.15)
    house_ratio = rng.uniform(0.2, 1.5)
    total = 3 * lens_ratio + 2 * gap + house_ratio
    width = height_px / total                              # before the transform
    s = UP if width < 20 else 3 if width < 40 else 2
    W = max(6, int(round(width * s)))
    lens_h, gap_h, house_h = (int(round(v * W)) for v in (lens_ratio, gap, house_ratio))
    pole_kind = int(rng.integers(3))                       # 0 pole, 1 bracket, 2 nothing
    pole_h = int(W * rng.uniform(1.0, 5.0)) if pole_kind == 0 else (int(W * 0.25) if pole_kind == 1 else 0)
    body_h = 3 * lens_h + 2 * gap_h + house_h
    pad = int(W * 1.3)
    H = body_h + pole_h + 2 * pad
    Wc = W + 2 * pad
    colour = np.zeros((H, Wc, 3), np.float32)
    alpha = np.zeros((H, Wc), np.float32)
    lit_mask = np.zeros((H, Wc, 3), np.float32)
    truth = np.zeros((H, Wc), np.float32)
    x0, x1 = pad, pad + W
    y = pad
    # housing
    hk = int(rng.integers(4))
    if hk == 0:
        hc = np.full(3, rng.uniform(10, 50))
    elif hk == 1:
        hc = np.full(3, rng.uniform(70, 150)) + rng.uniform(-10, 10, 3)
    elif hk == 2:
        hc = np.full(3, rng.uniform(200, 245))
    else:
        hc = None                                          # chrome gradient
    top = int(rng.integers(3))
    hmask = np.zeros((H, Wc), np.float32)
    if top == 0:
        cv2.rectangle(hmask, (x0, y), (x1 - 1, y + house_h), 1.0, -1)
    elif top == 1:
        _rounded(hmask, x0, y, x1 - 1, y + house_h + W // 3, W // 3, 1.0)
        cv2.rectangle(hmask, (x0, y + house_h // 2), (x1 - 1, y + house_h), 1.0, -1)
    else:
        step = max(1, house_h // 3)
        cv2.rectangle(hmask, (x0 + W // 6, y), (x1 - 1 - W // 6, y + step), 1.0, -1)
        cv2.rectangle(hmask, (x0, y + step), (x1 - 1, y + house_h), 1.0, -1)
    if hc is None:
        xs = np.linspace(-1, 1, Wc)
        grad = 90 + 120 * np.exp(-((xs - rng.uniform(-0.5, 0.5)) / 0.3) ** 2)
        hcol = np.repeat(grad[None, :, None], H, axis=0).repeat(3, axis=2)
    else:
        hcol = np.broadcast_to(hc.astype(np.float32), (H, Wc, 3))
    colour = np.where(hmask[:, :, None] > 0, hcol, colour).astype(np.float32)
    alpha = np.maximum(alpha, hmask)
    truth = np.maximum(truth, hmask)
    y += house_h
    # lenses, red on top
    radius = int(W * rng.uniform(0.0, 0.33))
    bands = int(rng.integers(0, 7))
    unlit_kind = int(rng.integers(3))
    stripe = rng.uniform(0.15, 0.6)
    for k, light in enumerate((2, 1, 0)):
        ly0, ly1 = y, y + lens_h
        m = np.zeros((H, Wc), np.float32)
        _rounded(m, x0, ly0, x1 - 1, ly1 - 1, radius, 1.0)
        lit = bool((state >> light) & 1)
        yy = np.linspace(0, 1, H)[:, None, None]
        if lit:
            pal = LIT[light]
            base = np.array(pal[int(rng.integers(len(pal)))], np.float32)
            xs = np.linspace(-1, 1, Wc)[None, :, None] * Wc / W
            hot = np.exp(-(xs / stripe) ** 2)
            c = base * (1 - 0.8 * hot) + 255.0 * 0.8 * hot
            c = np.broadcast_to(c, (H, Wc, 3))
            lit_mask += m[:, :, None] * base[None, None, :] / 255.0
        else:
            tint = np.array(TINT[light], np.float32)
            if unlit_kind == 0:
                c = tint * rng.uniform(40, 110)
            elif unlit_kind == 1:
                c = rng.uniform(90, 170) * (0.75 + 0.25 * tint)
            else:
                c = rng.uniform(190, 235) * (0.9 + 0.1 * tint)
            c = np.broadcast_to(c.astype(np.float32), (H, Wc, 3)).copy()
            hx = int(x0 + W * rng.uniform(0.15, 0.85))
            cv2.line(c, (hx, ly0 + 2), (hx, ly1 - 3), (250, 250, 250), max(1, W // 12))
        grad = 1.0 + rng.uniform(-0.15, 0.15) * (yy - 0.5)
        c = c * grad
        if bands:
            ph = (np.arange(H)[:, None, None] - ly0) / max(1, lens_h) * bands * 2 * math.pi
            c = c * (1 - 0.08 * (np.cos(ph) > 0.6))
        colour = np.where(m[:, :, None] > 0, c, colour).astype(np.float32)
        alpha = np.maximum(alpha, m)
        truth = np.maximum(truth, m)
        y = ly1
        if k < 2:
            if gap_kind == 1:
                cv2.rectangle(colour, (x0, y), (x1 - 1, y + gap_h), (15, 15, 15), -1)
                cv2.rectangle(alpha, (x0, y), (x1 - 1, y + gap_h), 1.0, -1)
                cv2.rectangle(truth, (x0, y), (x1 - 1, y + gap_h), 1.0, -1)
            elif gap_kind == 2:
                g = rng.uniform(120, 220)
                cv2.rectangle(colour, (x0 - W // 20, y), (x1 - 1 + W // 20, y + gap_h), (g, g, g), -1)
                cv2.rectangle(alpha, (x0 - W // 20, y), (x1 - 1 + W // 20, y + gap_h), 1.0, -1)
                cv2.rectangle(truth, (x0 - W // 20, y), (x1 - 1 + W // 20, y + gap_h), 1.0, -1)
            y += gap_h
    # below: pole or bracket
    if pole_kind == 0:
        pw = max(2, int(W * rng.uniform(0.2, 0.6)))
        pc = rng.uniform(60, 200)
        cv2.rectangle(colour, (pad + W // 2 - pw // 2, y), (pad + W // 2 + pw // 2, y + pole_h), (pc, pc, pc), -1)
        cv2.rectangle(alpha, (pad + W // 2 - pw // 2, y), (pad + W // 2 + pw // 2, y + pole_h), 1.0, -1)
    elif pole_kind == 1:
        bw = int(W * rng.uniform(1.2, 2.0))
        pc = rng.uniform(30, 160)
        cv2.rectangle(colour, (pad + W // 2 - bw // 2, y), (pad + W // 2 + bw // 2, y + pole_h), (pc, pc, pc), -1)
        cv2.rectangle(alpha, (pad + W // 2 - bw // 2, y), (pad + W // 2 + bw // 2, y + pole_h), 1.0, -1)
    if rng.random() < 0.35:                                # a drawn outline
        edge = cv2.morphologyEx((alpha > 0.5).astype(np.uint8), cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8))
        colour[edge > 0] = 20.0
    # the glow: growing, fading copies of the lit lenses
    glow = np.zeros_like(colour)
    if lit_mask.max() > 0:                                 # made at the final scale, then enlarged
        strength = rng.uniform(0.0, 1.0)
        reach = rng.uniform(0.2, 1.0) * W / s
        small = cv2.resize(lit_mask, (max(1, Wc // s), max(1, H // s)), interpolation=cv2.INTER_AREA)
        acc = np.zeros_like(small)
        for i in range(1, 5):
            r = max(1, int(round(reach * i / 4)))
            grown = cv2.dilate(small, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
            acc += cv2.GaussianBlur(grown, (0, 0), r / 2 + 0.5) * 255.0 * strength * (0.5 ** i)
        glow = cv2.resize(acc, (Wc, H), interpolation=cv2.INTER_LINEAR)
    # the transform: rotation, shear, squash about the body's centre
    ang = math.radians(rng.uniform(-10, 10))
    shear = rng.uniform(-0.12, 0.12)
    squash = math.exp(rng.uniform(-0.2, 0.2))
    cx, cy = Wc / 2, pad + body_h / 2
    a = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]]) @ \
        np.array([[squash, shear], [0.0, 1.0]])
    m = np.hstack([a, (np.array([cx, cy]) - a @ np.array([cx, cy]))[:, None]])
    warp = [cv2.warpAffine(v, m, (Wc, H), flags=cv2.INTER_LINEAR, borderValue=0)
            for v in (colour, alpha, glow, truth)]
    size = (max(1, Wc // s), max(1, H // s))
    colour, alpha, glow, truth = (cv2.resize(v, size, interpolation=cv2.INTER_AREA) for v in warp)
    ys, xs = np.nonzero(truth > 0.5)
    box = (float(xs.min()), float(ys.min()), float(xs.max() + 1 - xs.min()), float(ys.max() + 1 - ys.min())) \
        if len(xs) else (0.0, 0.0, 0.0, 0.0)
    return Sprite(colour, alpha, glow, box)


def stamp(img: np.ndarray, spr: Sprite, ox: int, oy: int) -> None:
    """Lay ``spr`` into ``img`` (float32 BGR 0..255, in place) with its corner at (ox, oy)."""
    H, W = img.shape[:2]
    h, w = spr.alpha.shape
    x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + w, W), min(oy + h, H)
    if x1 <= x0 or y1 <= y0:
        return
    sl = (slice(y0 - oy, y1 - oy), slice(x0 - ox, x1 - ox))
    region = img[y0:y1, x0:x1]
    g = np.clip(spr.glow[sl], 0, 255)
    region = 255.0 - (255.0 - region) * (255.0 - g) / 255.0           # screen blend
    a = spr.alpha[sl][:, :, None]
    img[y0:y1, x0:x1] = region * (1 - a) + spr.colour[sl] * a
