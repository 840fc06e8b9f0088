"""Drawn signal towers for training, and pasting them onto other images.

One renderer teaches a model that renderer; the towers drawn here span a
wide family instead, every property drawn per tower:

- **proportions**: lens height 0.75-1.25 tower widths, an unlit border in
  each lens (0-20 %), separator rings or none, a base ring or none, a
  housing 0.5-1.8 widths high with a flat, domed or stepped top, housing
  and rings up to 15 % wider than the lenses;
- **view**: the camera 35 degrees above to 35 below the tower's middle, so
  the rims between pieces bend into elliptical arcs and the housing's top
  or the bottom face shows; afterwards a turn of up to 6 degrees, a shear
  of up to 0.08 and a squash of up to 12 % across;
- **materials**: a key light from any side in front, ambient, one or two
  specular streaks, darker rims; housings black to white or metal; unlit
  lenses tinted plastic from dark to milky white, or clear with the LED
  board showing; lit lenses emitters of a broad hue range per colour,
  from dim to far over full scale (their core clips to white, a saturated
  channel bleeding into the others), brightest where they face the
  camera or evenly bright, with ribs, rows of LEDs or a dotted LED grid;
- **glow**: a halo of the lit lenses, 0.15-1.5 widths wide, of random
  strength, laid over whatever is behind, and spill onto the neighbouring
  pieces;
- **below**: nothing, a pole (thin or thick, grey, metal or black), a
  bracket plate or a box.

Shading is done in linear light and the result put through an sRGB
curve.  :func:`drawn_tower` returns a :class:`Sprite` (colour, coverage,
glow and the truth box: housing to bottom lens, like the project's labels);
:func:`paste` lays one onto an image.  Colour images are BGR.
"""
from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass

import cv2
import numpy as np

# the real tower (Festo #549843): 36 mm wide, three 34 mm segments with a 5 mm unlit border, a housing
SEGMENT_MM, BORDER_MM, HOUSING_MM, WIDTH_MM = 34.0, 5.0, 45.0, 36.0
#: hue ranges (0..1) of lit lenses: green, yellow, red
LIT_HUE = ((0.22, 0.45), (0.07, 0.18), (-0.06, 0.03))
#: hue of the unlit plastic: green, yellow, red
UNLIT_HUE = (0.33, 0.12, 0.0)


@dataclass
class Sprite:
    colour: np.ndarray        # h x w x 3 float32, BGR 0..255
    alpha: np.ndarray         # h x w float32 coverage
    glow: np.ndarray          # h x w x 3 float32, BGR light added around (and on) lit lenses
    box: tuple[int, int, int, int]   # the tower (housing to bottom lens) in the sprite, pixels


def _rgb(h: float, s: float, v: float) -> np.ndarray:
    """Linear RGB of an sRGB-ish HSV colour."""
    c = np.array(colorsys.hsv_to_rgb(h % 1.0, float(np.clip(s, 0, 1)), float(np.clip(v, 0, 1))))
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _to_srgb(lin: np.ndarray, bleed: float) -> np.ndarray:
    over = np.clip(lin.max(axis=-1, keepdims=True) - 1.0, 0, None)
    c = np.clip(lin + bleed * over, 0, 1)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055) * 255.0


@dataclass
class _Piece:
    z0: float                 # from the top, in tower widths
    z1: float
    radius: float             # in half widths (1: the lenses)
    kind: str                 # "housing", "cap", "lens", "border", "ring", "base", "pole", "box"
    light: int = -1           # lens and border: 0 green, 1 yellow, 2 red


def _layout(rng: np.random.Generator) -> tuple[list[_Piece], float]:
    """The pieces from the top (housing) down, and where the tower ends."""
    lens = rng.uniform(0.75, 1.25)
    border = lens * (rng.uniform(0.0, 0.2) if rng.random() < 0.7 else 0.0)
    ring = rng.uniform(0.03, 0.2) if rng.random() < 0.4 else 0.0
    house = rng.uniform(0.5, 1.8)
    house_r = rng.uniform(0.92, 1.15)
    pieces = []
    z = 0.0
    cap = int(rng.integers(3))
    if cap == 1:                                         # dome: three shrinking steps
        for f in (0.55, 0.8, 0.95):
            h = house * 0.1
            pieces.append(_Piece(z, z + h, house_r * f, "cap"))
            z += h
        pieces.append(_Piece(z, house, house_r, "housing"))
        z = house
    elif cap == 2:                                       # a narrower step on top
        h = house * rng.uniform(0.15, 0.35)
        pieces.append(_Piece(z, z + h, house_r * rng.uniform(0.6, 0.85), "cap"))
        pieces.append(_Piece(z + h, house, house_r, "housing"))
        z = house
    else:
        pieces.append(_Piece(z, house, house_r, "housing"))
        z = house
    ring_r = rng.uniform(1.0, 1.1)
    for i, light in enumerate((2, 1, 0)):
        if border > 0:
            pieces.append(_Piece(z, z + border / 2, 1.0, "border", light))
            pieces.append(_Piece(z + border / 2, z + lens - border / 2, 1.0, "lens", light))
            pieces.append(_Piece(z + lens - border / 2, z + lens, 1.0, "border", light))
        else:
            pieces.append(_Piece(z, z + lens, 1.0, "lens", light))
        z += lens
        if ring > 0 and i < 2:
            pieces.append(_Piece(z, z + ring, ring_r, "ring"))
            z += ring
    if rng.random() < 0.5:
        base = rng.uniform(0.05, 0.3)
        pieces.append(_Piece(z, z + base, rng.uniform(1.0, 1.15), "base"))
        z += base
    end = z
    below = rng.random()
    if below < 0.45:
        pieces.append(_Piece(z, z + end * rng.uniform(0.3, 4.0), rng.uniform(0.15, 0.8), "pole"))
    elif below < 0.6:
        pieces.append(_Piece(z, z + rng.uniform(0.08, 0.3), rng.uniform(1.3, 2.5), "ring"))
    elif below < 0.8:
        pieces.append(_Piece(z, z + end * rng.uniform(0.3, 1.5), rng.uniform(2.0, 6.0), "box"))
    return pieces, end


@dataclass
class _Look:
    light_az: float
    light_el: float
    ambient: float
    key: float
    key_colour: np.ndarray
    streaks: list[tuple[float, float, float]]     # (position across -1..1, width, strength)
    rim: float
    housing: np.ndarray
    metal: float
    ring: np.ndarray
    pole: np.ndarray
    unlit: list[np.ndarray]
    clear: bool
    emission: list[np.ndarray]
    falloff: float
    texture: int                                   # 0 none, 1 ribs, 2 LED rows, 3 LED dots
    texture_n: int
    texture_depth: float
    spill: float
    bleed: float


def _look(rng: np.random.Generator) -> _Look:
    kind = rng.random()
    if kind < 0.5:
        housing = _rgb(rng.uniform(0, 1), rng.uniform(0, 0.25), rng.uniform(0.03, 0.25))
    elif kind < 0.75:
        housing = _rgb(rng.uniform(0, 1), rng.uniform(0, 0.3), rng.uniform(0.3, 0.65))
    else:
        housing = _rgb(rng.uniform(0, 1), rng.uniform(0, 0.12), rng.uniform(0.65, 0.97))
    clear = rng.random() < 0.3
    unlit = []
    for light in range(3):
        h = UNLIT_HUE[light] + rng.uniform(-0.04, 0.04)
        if clear:
            unlit.append(_rgb(h, rng.uniform(0.0, 0.35), rng.uniform(0.35, 0.9)))
        else:
            unlit.append(_rgb(h, rng.uniform(0.25, 0.95), rng.uniform(0.08, 0.65)))
    ambient, key = rng.uniform(0.15, 0.8), rng.uniform(0.0, 1.2)
    key_colour = _rgb(rng.uniform(0.0, 0.65), rng.uniform(0.0, 0.3), 1.0)
    # a lit lens outshines the brightest unlit one at least twice (a tower whose lit and unlit
    # lenses look alike cannot be read, by a network or a person)
    unlit_peak = max(float(u.max()) for u in unlit) * (ambient + key * float(key_colour.max()))
    gain = max(float(np.exp(rng.uniform(math.log(0.6), math.log(5.0)))), 2.0 * unlit_peak / 0.75)
    emission = []
    for light in range(3):
        lo, hi = LIT_HUE[light]
        e = _rgb(rng.uniform(lo, hi), rng.uniform(0.55, 1.0), 1.0)
        emission.append(e / max(float(e.max()), 1e-6) * gain * rng.uniform(0.75, 1.25))
    streaks = [(rng.uniform(-0.8, 0.8), rng.uniform(0.03, 0.25), rng.uniform(0.0, 0.9))
               for _ in range(int(rng.integers(0, 3)))]
    return _Look(light_az=rng.uniform(-1.7, 1.7), light_el=rng.uniform(-0.3, 1.2),
                 ambient=ambient, key=key, key_colour=key_colour,
                 streaks=streaks, rim=rng.uniform(0.0, 0.7), housing=housing, metal=rng.uniform(0, 0.7),
                 ring=_rgb(rng.uniform(0, 1), rng.uniform(0, 0.2), rng.uniform(0.03, 0.8)),
                 pole=_rgb(rng.uniform(0, 1), rng.uniform(0, 0.2), rng.uniform(0.05, 0.85)),
                 unlit=unlit, clear=clear, emission=emission, falloff=rng.uniform(0.0, 2.0),
                 texture=int(rng.choice([0, 0, 1, 2, 3])), texture_n=int(rng.integers(3, 24)),
                 texture_depth=rng.uniform(0.05, 0.45), spill=rng.uniform(0.0, 0.5), bleed=rng.uniform(0.0, 0.7))


def drawn_tower(rng: np.random.Generator, height: float, state: int) -> Sprite:
    """A tower ``height`` pixels high (housing to bottom lens, before the
    final turn and squash) showing ``state`` (green 1, yellow 2, red 4)."""
    pieces, end = _layout(rng)
    look = _look(rng)
    width = max(2.0, height / end)                     # pixels per tower width
    s = int(np.clip(math.ceil(28.0 / width), 2, 6))    # drawn at s times and reduced
    wp = width * s
    elev = rng.uniform(-0.6, 0.6)                      # radians, + from above
    k = math.sin(elev) * 0.5                           # ellipse half height per half width... in widths
    bottom = max(p.z1 for p in pieces)
    r_max = max(p.radius for p in pieces)
    pad = int(wp * (0.3 + 0.5 * r_max))
    H = int(math.ceil((bottom + 2 * abs(k) + 0.2) * wp)) + 2 * pad
    W = int(math.ceil(r_max * wp)) + 2 * pad
    cx = W / 2.0
    top = pad + abs(k) * wp
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    xn = (xs + 0.5 - cx) / (wp / 2)                    # across, in half widths
    lin = np.zeros((H, W, 3), np.float32)
    alpha = np.zeros((H, W), np.float32)
    emit = np.zeros((H, W, 3), np.float32)
    truth = np.zeros((H, W), np.float32)
    light_dir = np.array([math.sin(look.light_az) * math.cos(look.light_el), math.sin(look.light_el),
                          math.cos(look.light_az) * math.cos(look.light_el)], np.float32)
    # front surface of each piece: the rim curves by the view's ellipse
    for p in pieces:
        inside = np.abs(xn) <= p.radius
        if not inside.any():
            continue
        bend = k * np.sqrt(np.clip(p.radius ** 2 - xn ** 2, 0, None)) * wp / 2
        y0, y1 = top + p.z0 * wp + bend, top + p.z1 * wp + bend
        m = inside & (ys + 0.5 >= y0) & (ys + 0.5 < y1)
        if k > 0 and p is pieces[0]:                   # the top face, seen from above
            face = inside & (ys + 0.5 >= top + p.z0 * wp - bend) & (ys + 0.5 < y0)
            lin[face] = _material(look, p, np.zeros(int(face.sum()), np.float32), light_dir, face=True)
            alpha[face] = 1.0
            truth[face] = 1.0
        if not m.any():
            continue
        theta = np.arcsin(np.clip(xn[m] / p.radius, -1, 1))
        lin[m] = _material(look, p, theta, light_dir)
        alpha[m] = 1.0
        if p.kind not in ("pole", "box") and p.z1 <= end + 1e-6:
            truth[m] = 1.0
        if p.kind == "lens" and (state >> p.light) & 1:
            e = _emission(look, p, theta, (ys[m] + 0.5 - y0[m]) / np.maximum(y1[m] - y0[m], 1e-3))
            lin[m] = e + 0.15 * lin[m]
            emit[m] = e
    if look.spill > 0 and emit.any():                   # lit lenses light their neighbours
        reach = max(1.0, wp * 0.3)
        near = cv2.GaussianBlur(emit, (0, 0), reach)
        lin += look.spill * near * alpha[:, :, None] * (emit.max(axis=2, keepdims=True) == 0)
    colour = _to_srgb(lin, look.bleed).astype(np.float32)
    # the view's last touch: turn, shear, squash about the tower's middle
    ang = math.radians(rng.uniform(-6, 6))
    shear = rng.uniform(-0.08, 0.08)
    squash = math.exp(rng.uniform(-0.12, 0.12))
    mid = np.array([cx, top + end * wp / 2])
    turn = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    a = turn @ np.array([[squash, shear], [0, 1]])
    mat = np.hstack([a, (mid - a @ mid)[:, None]]).astype(np.float32)
    size = (max(1, int(round(W / s))), max(1, int(round(H / s))))
    out = []
    for v in (colour[:, :, ::-1], alpha, np.minimum(emit, 3.0)[:, :, ::-1], truth):
        v = cv2.warpAffine(np.ascontiguousarray(v), mat, (W, H), flags=cv2.INTER_LINEAR, borderValue=0)
        out.append(cv2.resize(v, size, interpolation=cv2.INTER_AREA))
    colour, alpha, emit, truth = out
    # the glow, at the final scale on a canvas wide enough for it
    glow = np.zeros_like(colour)
    strength = rng.uniform(0.0, 1.0) if rng.random() < 0.8 else 0.0
    if strength > 0 and emit.max() > 0:
        spread = rng.uniform(0.15, 1.5)
        strength /= 1.0 + spread                       # a wide glow is a faint one
        sigma = width * spread
        g_pad = int(math.ceil(2.5 * sigma))
        colour, alpha, emit, truth = (cv2.copyMakeBorder(v, g_pad, g_pad, g_pad, g_pad, cv2.BORDER_CONSTANT, value=0)
                                      for v in (colour, alpha, emit, truth))
        g = cv2.GaussianBlur(emit, (0, 0), sigma)
        g = g / max(float(g.max()), 1e-6) * min(1.0, float(emit.max()))
        glow = _to_srgb(g * strength, 0.0).astype(np.float32)
    ys_t, xs_t = np.nonzero(truth > 0.5)
    if len(ys_t) == 0:
        box = (0, 0, 0, 0)
    else:
        box = (int(xs_t.min()), int(ys_t.min()), int(xs_t.max() - xs_t.min() + 1), int(ys_t.max() - ys_t.min() + 1))
    return Sprite(colour.astype(np.float32), alpha.astype(np.float32), glow.astype(np.float32), box)


def _material(look: _Look, p: _Piece, theta: np.ndarray, light_dir: np.ndarray, face: bool = False) -> np.ndarray:
    """Linear RGB of a piece's surface at angles ``theta`` across the cylinder (0 facing the camera)."""
    if face:
        n = np.tile(np.array([0.0, 1.0, 0.0], np.float32), (len(theta), 1))
    else:
        n = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    diffuse = np.clip(n @ light_dir, 0, None)[:, None]
    rim = 1.0 - look.rim * (1.0 - np.cos(theta))[:, None] ** 2
    spec = np.zeros((len(theta), 1), np.float32)
    x = np.sin(theta)
    for pos, width, strength in look.streaks:
        spec[:, 0] += strength * np.exp(-((x - pos) / width) ** 2)
    if p.kind in ("housing", "cap"):
        alb, shine = look.housing, 0.3 + look.metal
    elif p.kind in ("ring", "base", "box"):
        alb, shine = look.ring, 0.5 + look.metal
    elif p.kind == "pole":
        alb, shine = look.pole, 0.6
    else:
        alb, shine = look.unlit[p.light], 0.8
        if p.kind == "border":
            alb = alb * 0.6
        elif look.clear:                                  # the LED board through clear plastic
            alb = alb * (1.0 - 0.35 * np.exp(-(x / 0.35) ** 2))[:, None]
    body = alb * (look.ambient + look.key * look.key_colour * diffuse) * rim
    return (body + shine * spec * look.key_colour).astype(np.float32)


def _emission(look: _Look, p: _Piece, theta: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Linear RGB light of a lit lens at angles ``theta`` and heights ``v`` (0..1 down the lens)."""
    e = look.emission[p.light][None, :]
    prof = 0.3 + 0.7 * np.cos(theta) ** look.falloff
    mod = np.ones_like(theta)
    x = np.sin(theta)
    n, d = look.texture_n, look.texture_depth
    if look.texture == 1:
        mod *= 1 + d * np.cos(n * theta * 2)
    elif look.texture == 2:
        mod *= 1 - d * 0.5 * (1 - np.cos(2 * math.pi * max(2, n // 4) * v))
    elif look.texture == 3:
        mod *= 1 - d * 0.25 * (1 - np.cos(2 * math.pi * max(2, n // 4) * v)) * (1 - np.cos(math.pi * 3 * x))
    return (e * (prof * mod)[:, None]).astype(np.float32)


def paste(dst: np.ndarray, sprite: Sprite, x: int, y: int) -> tuple[int, int, int, int]:
    """Lay ``sprite`` into ``dst`` (uint8 BGR, in place) with its tower's box
    at (x, y): its glow added, then its colour over by coverage.  Returns
    the tower's box in ``dst`` clipped to it."""
    bx, by, bw, bh = sprite.box
    ox, oy = x - bx, y - by
    h, w = sprite.alpha.shape
    H, W = dst.shape[:2]
    x0, y0, x1, y1 = max(ox, 0), max(oy, 0), min(ox + w, W), min(oy + h, H)
    if x1 > x0 and y1 > y0:
        sl = (slice(y0 - oy, y1 - oy), slice(x0 - ox, x1 - ox))
        region = dst[y0:y1, x0:x1].astype(np.float32) + sprite.glow[sl]
        a = sprite.alpha[sl][:, :, None]
        dst[y0:y1, x0:x1] = np.clip(region * (1 - a) + sprite.colour[sl] * a, 0, 255).astype(np.uint8)
    tx0, ty0 = max(x, 0), max(y, 0)
    tx1, ty1 = min(x + bw, W), min(y + bh, H)
    return (tx0, ty0, max(0, tx1 - tx0), max(0, ty1 - ty0))
