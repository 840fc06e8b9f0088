"""Renderer B: signal towers ray-cast as stacked cylinders, for evaluation only.

Made independently of the PyBullet scenes (:mod:`backends.sim.camera`)
and of the towers training draws (:mod:`..synth`): its own geometry,
materials, light model and camera, so that a model trained on one and
tested here measures reading a signal tower, not fitting a renderer.
Training never imports this package (a test checks it).

A tower is a surface of revolution of coaxial pieces along +z: an
optional pole, a base ring, three lenses (green at the bottom, yellow,
red) with optional separator rings, a housing and a flat or stepped-dome
cap.  Every proportion is drawn per tower (lens height 1.3-2.5 radii,
rings up to a fifth of a lens, housings half to one and a half lenses
high).  A pinhole camera looks at the tower's middle from -28 to +28
degrees of elevation (top and bottom rims become ellipses) with a roll of
up to 8 degrees; every pixel's ray is intersected with the pieces'
walls and rims, supersampled three times.

Shading, in linear light: a key light (direction, colour temperature,
strength) and an ambient term taken from the backdrop photograph; opaque
parts Lambert + Blinn-Phong with a metal share that reflects a blurred
copy of the photograph; unlit lenses translucent tinted plastic (or
frosted, nearly clear) with a Schlick rim and a sharp highlight; lit
lenses emitters, brightest where they face the camera, with optional
ribs and rows of LEDs, 0.8 to 5 times full scale.  The glow of lit
lenses (a halo and a wide veil) is laid over the backdrop by
:mod:`.compose`.

The truth box is the silhouette of housing, lenses and rings (not the
pole), like the project's own labels.
"""
from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass

import cv2
import numpy as np

SUPERSAMPLE = 3
#: hue (0..1) ranges of the lit emission: green, yellow, red
LIT_HUES = ((0.26, 0.42), (0.09, 0.16), (-0.02, 0.025))


@dataclass
class Piece:
    z0: float
    z1: float
    radius: float
    kind: str                  # "pole", "ring", "lens", "housing"
    index: int = -1            # lens: 0 green, 1 yellow, 2 red
    truth: bool = True         # part of the labelled tower outline


@dataclass
class Tower:
    """One tower's geometry and materials (units: lens radii)."""
    pieces: list[Piece]
    state: int
    unlit: list[np.ndarray]            # linear RGB tint per lens
    emission: list[np.ndarray]         # linear RGB (HDR) per lens
    frosted: list[bool]
    albedo: dict[str, np.ndarray]      # "housing", "ring", "pole": linear RGB
    metal: dict[str, float]
    shininess: float
    ribs: int
    rib_depth: float
    led_rows: int
    led_depth: float
    falloff: float                     # emission ~ (n.v) ** falloff

    @property
    def top(self) -> float:
        return max(p.z1 for p in self.pieces if p.truth)

    @property
    def bottom(self) -> float:
        return min(p.z0 for p in self.pieces if p.truth)


def _hsv(h: float, s: float, v: float) -> np.ndarray:
    return np.array(colorsys.hsv_to_rgb(h % 1.0, s, v), np.float64)


def _srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def random_tower(rng: np.random.Generator, state: int) -> Tower:
    """A tower with every proportion and material drawn from ``rng``."""
    lens_h = rng.uniform(1.3, 2.5)
    ring_h = lens_h * (rng.uniform(0.02, 0.2) if rng.random() < 0.75 else 0.0)
    ring_r = rng.uniform(1.0, 1.07)
    pieces: list[Piece] = []
    z = 0.0
    base_h = lens_h * rng.uniform(0.0, 0.3)
    if rng.random() < 0.75:
        length = rng.uniform(1.0, 12.0)
        pieces.append(Piece(-length, 0.0, rng.uniform(0.25, 0.9), "pole", truth=False))
    if base_h > 0.02:
        pieces.append(Piece(z, z + base_h, rng.uniform(1.0, 1.15), "ring"))
        z += base_h
    for i in range(3):
        pieces.append(Piece(z, z + lens_h, 1.0, "lens", i))
        z += lens_h
        if ring_h > 0 and i < 2:
            pieces.append(Piece(z, z + ring_h, ring_r, "ring"))
            z += ring_h
    house_h = lens_h * rng.uniform(0.5, 1.6)
    house_r = rng.uniform(0.95, 1.12)
    if rng.random() < 0.4:                               # stepped dome
        steps = 4
        for k in range(steps):
            frac = math.cos(0.5 * math.pi * k / steps)
            h = house_h * (0.6 if k == 0 else 0.4 / (steps - 1))
            pieces.append(Piece(z, z + h, house_r * max(frac, 0.35), "housing"))
            z += h
    else:
        pieces.append(Piece(z, z + house_h, house_r, "housing"))
        z += house_h

    unlit, emission, frosted = [], [], []
    gain = rng.uniform(0.8, 5.0)
    for i in range(3):
        lo, hi = LIT_HUES[i]
        hue = rng.uniform(lo, hi)
        fr = rng.random() < 0.25
        frosted.append(fr)
        if fr:
            tint = _hsv(hue, rng.uniform(0.0, 0.3), rng.uniform(0.3, 0.75))
        else:
            tint = _hsv(hue + rng.uniform(-0.02, 0.02), rng.uniform(0.3, 0.95), rng.uniform(0.08, 0.55))
        unlit.append(_srgb_to_linear(tint))
        e = _srgb_to_linear(_hsv(hue, rng.uniform(0.75, 1.0), 1.0))
        emission.append(e / max(e.max(), 1e-6) * gain * rng.uniform(0.8, 1.2))
    house_kind = rng.random()
    if house_kind < 0.45:
        house = _hsv(rng.uniform(0, 1), rng.uniform(0, 0.2), rng.uniform(0.03, 0.2))      # black, anthracite
    elif house_kind < 0.8:
        house = _hsv(rng.uniform(0.5, 0.7), rng.uniform(0, 0.25), rng.uniform(0.3, 0.7))  # greys, blue-grey
    else:
        house = _hsv(rng.uniform(0, 1), rng.uniform(0, 0.1), rng.uniform(0.75, 0.95))     # white, silver
    albedo = {"housing": _srgb_to_linear(house),
              "ring": _srgb_to_linear(_hsv(rng.uniform(0, 1), rng.uniform(0, 0.15), rng.uniform(0.05, 0.8))),
              "pole": _srgb_to_linear(_hsv(rng.uniform(0, 1), rng.uniform(0, 0.2), rng.uniform(0.1, 0.85)))}
    metal = {"housing": rng.uniform(0, 0.6), "ring": rng.uniform(0, 0.9), "pole": rng.uniform(0, 0.9)}
    return Tower(pieces, state, unlit, emission, frosted, albedo, metal,
                 shininess=float(np.exp(rng.uniform(np.log(8), np.log(200)))),
                 ribs=int(rng.integers(10, 32)) if rng.random() < 0.5 else 0, rib_depth=rng.uniform(0.05, 0.35),
                 led_rows=int(rng.integers(2, 7)) if rng.random() < 0.35 else 0, led_depth=rng.uniform(0.1, 0.5),
                 falloff=rng.uniform(0.0, 1.5))


@dataclass
class Light:
    """Key light (unit direction towards it, linear RGB) and ambient (linear RGB)."""
    direction: np.ndarray
    colour: np.ndarray
    ambient: np.ndarray
    env: np.ndarray                  # small blurred linear backdrop for reflections (h x w x 3)


def random_light(rng: np.random.Generator, backdrop_linear: np.ndarray) -> Light:
    az, el = rng.uniform(-math.pi, math.pi), rng.uniform(-0.2, 1.4)
    d = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
    kelvin_tint = _hsv(rng.uniform(0.05, 0.6), rng.uniform(0.0, 0.3), 1.0)
    colour = _srgb_to_linear(kelvin_tint) * rng.uniform(0.3, 1.6)
    env = cv2.resize(backdrop_linear.astype(np.float32), (32, 16), interpolation=cv2.INTER_AREA)
    env = cv2.GaussianBlur(env, (0, 0), 1.5)
    mean = env.reshape(-1, 3).mean(axis=0).astype(np.float64)
    ambient = mean / max(float(mean.mean()), 1e-3) * rng.uniform(0.1, 0.6)
    return Light(d, colour, ambient, env)


@dataclass
class Patch:
    """A rendered tower: linear HDR colour, coverage, lit-emission layer and truth box (patch pixels)."""
    colour: np.ndarray               # h x w x 3 float32, linear, may exceed 1
    alpha: np.ndarray                # h x w float32
    emission: np.ndarray             # h x w x 3 float32, what glows
    box: tuple[float, float, float, float]


def _camera(rng: np.random.Generator, tower: Tower, height_px: float):
    """Eye, rotation (columns: right, down, forward in the tower frame), focal length in pixels."""
    elev = math.radians(rng.uniform(-28, 28))
    dist = rng.uniform(6.0, 90.0)                         # lens radii: ~10 cm to ~1.6 m for a 18 mm radius
    mid = 0.5 * (tower.top + tower.bottom)
    az = rng.uniform(-math.pi, math.pi)
    eye = np.array([dist * math.cos(elev) * math.cos(az), dist * math.cos(elev) * math.sin(az),
                    mid + dist * math.sin(elev)])
    target = np.array([0.0, 0.0, mid]) + rng.normal(0, 0.15, 3)
    fwd = target - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(fwd, right)
    roll = math.radians(rng.uniform(-8, 8))
    c, s = math.cos(roll), math.sin(roll)
    rot = np.column_stack([c * right + s * down, -s * right + c * down, fwd])
    span = tower.top - tower.bottom
    focal = height_px * dist / span                       # the labelled tower about height_px high
    return eye, rot, focal


def _hit(pieces: list[Piece], o: np.ndarray, d: np.ndarray):
    """Nearest hit of rays ``o + t d`` (N x 3) with the pieces: (t, piece index, normal)."""
    n = len(d)
    best_t = np.full(n, np.inf)
    best_p = np.full(n, -1, np.int64)
    normal = np.zeros((n, 3))
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    b = 2 * (o[:, 0] * d[:, 0] + o[:, 1] * d[:, 1])
    oo = o[:, 0] ** 2 + o[:, 1] ** 2
    for k, p in enumerate(pieces):
        disc = b * b - 4 * a * (oo - p.radius ** 2)
        ok = (disc >= 0) & (a > 1e-12)
        t = np.where(ok, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * np.maximum(a, 1e-12)), np.inf)
        z = o[:, 2] + t * d[:, 2]
        ok &= (t > 0) & (z >= p.z0) & (z <= p.z1) & (t < best_t)
        best_t = np.where(ok, t, best_t)
        best_p = np.where(ok, k, best_p)
        hx, hy = o[:, 0] + t * d[:, 0], o[:, 1] + t * d[:, 1]
        normal[ok] = np.column_stack([hx[ok], hy[ok], np.zeros(int(ok.sum()))]) / p.radius
        for zc, sign in ((p.z1, 1.0), (p.z0, -1.0)):        # the rims: discs at both ends
            with np.errstate(divide="ignore", invalid="ignore"):
                tc = (zc - o[:, 2]) / d[:, 2]
            hx, hy = o[:, 0] + tc * d[:, 0], o[:, 1] + tc * d[:, 1]
            okc = np.isfinite(tc) & (tc > 0) & (hx ** 2 + hy ** 2 <= p.radius ** 2) & (tc < best_t) \
                & (sign * d[:, 2] < 0)
            best_t = np.where(okc, tc, best_t)
            best_p = np.where(okc, k, best_p)
            normal[okc] = (0.0, 0.0, sign)
    return best_t, best_p, normal


def _env(light: Light, r: np.ndarray) -> np.ndarray:
    """The blurred backdrop seen along reflected directions ``r`` (N x 3)."""
    h, w = light.env.shape[:2]
    u = ((np.arctan2(r[:, 1], r[:, 0]) / (2 * math.pi) + 0.5) * (w - 1)).astype(int)
    v = ((0.5 - np.arcsin(np.clip(r[:, 2], -1, 1)) / math.pi) * (h - 1)).astype(int)
    return light.env[np.clip(v, 0, h - 1), np.clip(u, 0, w - 1)].astype(np.float64)


def render_tower(rng: np.random.Generator, tower: Tower, light: Light, height_px: float) -> Patch:
    """Ray-cast ``tower`` with its truth box ``height_px`` pixels high (to a
    pixel: a first render measures it, the focal length is corrected)."""
    eye, rot, focal = _camera(rng, tower, height_px)
    patch = _render(tower, light, eye, rot, focal, height_px)
    if patch.box[3] > 0 and abs(patch.box[3] / height_px - 1) > 0.02:
        patch = _render(tower, light, eye, rot, focal * height_px / patch.box[3], height_px)
    return patch


def _render(tower: Tower, light: Light, eye: np.ndarray, rot: np.ndarray, focal: float,
            height_px: float) -> Patch:
    ss = SUPERSAMPLE
    # patch extent: project the whole geometry's bounding cylinder
    z_lo = min(p.z0 for p in tower.pieces)
    z_hi = max(p.z1 for p in tower.pieces)
    r_max = max(p.radius for p in tower.pieces)
    pts = np.array([(r_max * math.cos(a), r_max * math.sin(a), z) for z in (z_lo, z_hi)
                    for a in np.linspace(0, 2 * math.pi, 16, endpoint=False)])
    cam = (pts - eye) @ rot
    cam[:, 2] = np.maximum(cam[:, 2], 1e-3)
    u, v = focal * cam[:, 0] / cam[:, 2], focal * cam[:, 1] / cam[:, 2]
    limit = 3.0 * height_px                                  # a long pole leaves the patch
    u0, u1 = max(u.min(), -limit) - 2, min(u.max(), limit) + 2
    v0, v1 = max(v.min(), -limit) - 2, min(v.max(), limit) + 2
    w, h = int(math.ceil(u1 - u0)), int(math.ceil(v1 - v0))
    ys, xs = np.mgrid[0:h * ss, 0:w * ss].astype(np.float64)
    uu = u0 + (xs + 0.5) / ss
    vv = v0 + (ys + 0.5) / ss
    dirs = np.stack([uu / focal, vv / focal, np.ones_like(uu)], axis=-1).reshape(-1, 3) @ rot.T
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origin = np.broadcast_to(eye, dirs.shape)
    t, which, nrm = _hit(tower.pieces, origin, dirs)
    hit = which >= 0
    col = np.zeros((len(dirs), 3))
    emis = np.zeros((len(dirs), 3))
    truth = np.zeros(len(dirs), bool)
    if hit.any():
        idx = np.flatnonzero(hit)
        d, n, pk = dirs[idx], nrm[idx], which[idx]
        p = eye + t[idx, None] * d
        view = -d
        ndl = np.clip(n @ light.direction, 0, None)[:, None]
        half = light.direction[None, :] + view
        half /= np.linalg.norm(half, axis=1, keepdims=True)
        ndh = np.clip((n * half).sum(axis=1), 0, None)
        ndv = np.clip((n * view).sum(axis=1), 0, None)
        refl = d - 2 * (d * n).sum(axis=1, keepdims=True) * n
        env = _env(light, refl)
        fresnel = (0.04 + 0.96 * (1 - ndv) ** 5)[:, None]
        spec = (ndh ** tower.shininess)[:, None] * light.colour
        out = np.zeros((len(idx), 3))
        glow = np.zeros((len(idx), 3))
        phi = np.arctan2(p[:, 1], p[:, 0])
        for k, piece in enumerate(tower.pieces):
            m = pk == k
            if not m.any():
                continue
            truth[idx[m]] = piece.truth
            if piece.kind == "lens":
                i = piece.index
                if (tower.state >> i) & 1:
                    prof = (ndv[m] ** tower.falloff)[:, None]
                    mod = np.ones((int(m.sum()), 1))
                    if tower.ribs:
                        mod *= 1 + tower.rib_depth * np.cos(tower.ribs * phi[m])[:, None]
                    if tower.led_rows:
                        zz = (p[m, 2] - piece.z0) / max(piece.z1 - piece.z0, 1e-6)
                        mod *= 1 - tower.led_depth * 0.5 * (1 - np.cos(2 * math.pi * tower.led_rows * zz))[:, None]
                    e = tower.emission[i][None, :] * (0.35 + 0.65 * prof) * mod
                    out[m] = e + 0.3 * spec[m]
                    glow[m] = e
                else:
                    tint = tower.unlit[i][None, :]
                    wrap = (ndl[m] + 0.4) / 1.4
                    body = tint * (light.ambient[None, :] + light.colour[None, :] * wrap)
                    if tower.frosted[i]:
                        body = body * 1.2
                    out[m] = body * (1 - fresnel[m]) + fresnel[m] * env[m] + 0.8 * spec[m]
            else:
                key = piece.kind if piece.kind in tower.albedo else "housing"
                alb = tower.albedo[key][None, :]
                met = tower.metal[key]
                diffuse = alb * (light.ambient[None, :] + light.colour[None, :] * ndl[m])
                out[m] = (1 - met) * diffuse + met * env[m] * (0.3 + alb) + (0.2 + met) * spec[m]
        col[idx] = out
        emis[idx] = glow

    def down(a):
        return cv2.resize(a.reshape(h * ss, w * ss, -1).astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)

    colour = down(col).reshape(h, w, 3)
    alpha = down(hit.astype(np.float32)).reshape(h, w)
    emission = down(emis).reshape(h, w, 3)
    tmask = truth.reshape(h * ss, w * ss)
    ys_t, xs_t = np.nonzero(tmask)
    if len(ys_t) == 0:
        box = (0.0, 0.0, 0.0, 0.0)
    else:
        box = (xs_t.min() / ss, ys_t.min() / ss, (xs_t.max() + 1 - xs_t.min()) / ss,
               (ys_t.max() + 1 - ys_t.min()) / ss)
    return Patch(colour, alpha, emission, box)
