"""Camera rendering of the world: PyBullet's TinyRenderer plus what a
camera adds to it.

TinyRenderer shades every surface by one directional light (colour =
albedo x (ambient + diffuse x max(0, n.l)) + specular, clipped) and has no
emissive materials, so a lit LED would come out as shaded paint.  A view is
therefore made in five steps:

1. TinyRenderer draws colour and the segmentation mask (object and link of
   every pixel) under the :class:`Lighting`'s direction, intensity, ambient
   and specular share (white light);
2. reflected light is tinted by the illuminant's colour temperature
   (:func:`kelvin_rgb`, a black body);
3. the pixels of lit signal-light segments (``emitters``) are replaced by
   their emission: not shaded, brightest in the middle of the lens;
4. bloom: a blurred copy of everything brighter than full scale spills
   around it, as lens glare does;
5. the camera: exposure gain, white balance for ``white_balance`` kelvin,
   clipping at full scale (so over-exposed lights saturate towards white).

Images are BGR uint8; ``eye`` and ``rot`` are the camera position in the
field frame (metres) and the rotation taking optical-frame vectors (x right,
y down, z forward) into the field frame.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import cv2
import numpy as np

from rll_bt.backend import CameraIntrinsics

from .bullet import pybullet

NEAR, FAR = 0.02, 30.0
LINK_SHIFT = 24                     # segmentation value = body + ((link + 1) << 24)

# sRGB colour of a black body (normalised to its largest channel) at kelvin;
# values of the commonly tabulated black-body colour table
_KELVIN = np.array([1500, 2000, 2500, 3000, 3500, 4000, 4500, 5000, 5500, 6000, 6500, 7000, 8000, 10000, 12000],
                   float)
_KELVIN_RGB = np.array([
    (255, 109, 0), (255, 137, 14), (255, 161, 72), (255, 180, 107), (255, 196, 137), (255, 209, 163),
    (255, 219, 186), (255, 228, 206), (255, 236, 224), (255, 243, 239), (255, 249, 253), (245, 243, 255),
    (227, 233, 255), (204, 219, 255), (191, 211, 255)], float) / 255.0

#: linear emission of each lit light (R, G, B), before exposure; above 1 saturates
EMISSION = {"GREEN": (0.28, 1.90, 0.38), "YELLOW": (2.10, 1.45, 0.12), "RED": (2.30, 0.22, 0.14)}


def kelvin_rgb(kelvin: float) -> np.ndarray:
    """(R, G, B) of a black body at ``kelvin`` (1500-12000 K), largest channel 1."""
    return _kelvin_rgb(float(np.clip(kelvin, _KELVIN[0], _KELVIN[-1]))).copy()


@lru_cache(maxsize=64)
def _kelvin_rgb(k: float) -> np.ndarray:
    rgb = np.array([np.interp(k, _KELVIN, _KELVIN_RGB[:, i]) for i in range(3)])
    return rgb / rgb.max()


@dataclass(frozen=True)
class Lighting:
    """The hall's light and the camera's settings.

    ``azimuth``/``elevation`` (radians, field frame): where the light comes
    from; ``intensity`` scales the directional (diffuse) part, ``ambient``
    the light from everywhere, ``specular`` the shine; ``kelvin`` is the
    illuminant's colour temperature, ``white_balance`` the one the camera
    corrects for (equal: neutral greys), ``exposure`` the camera's gain,
    ``bloom`` the share of over-bright light spilt around it."""
    azimuth: float = 0.7
    elevation: float = 1.0
    intensity: float = 0.45
    ambient: float = 0.5
    specular: float = 0.08
    kelvin: float = 4500.0
    white_balance: float = 4500.0
    exposure: float = 1.0
    bloom: float = 0.25

    def __post_init__(self):
        for name in ("intensity", "ambient", "specular", "exposure", "bloom"):
            if getattr(self, name) < 0:
                raise ValueError(f"lighting {name} must not be negative, not {getattr(self, name)}")
        for name in ("kelvin", "white_balance"):
            if not 1000.0 <= getattr(self, name) <= 20000.0:
                raise ValueError(f"lighting {name} must be 1000-20000 K, not {getattr(self, name)}")

    @property
    def direction(self) -> list[float]:
        """Unit vector towards the light, field frame."""
        c = math.cos(self.elevation)
        return [c * math.cos(self.azimuth), c * math.sin(self.azimuth), math.sin(self.elevation)]

    def with_options(self, **changes) -> Lighting:
        return replace(self, **changes)

    @classmethod
    def random(cls, rng: np.random.Generator) -> Lighting:
        """Lighting drawn from what halls and cameras give: warm to cold light
        (2700-8000 K) with a camera balanced for a guess of it, dim to
        bright, from any side, soft to hard; the exposure is at most what
        keeps the brightest shaded surface near full scale (a camera's auto
        exposure), so only lights and glare clip."""
        kelvin = float(np.exp(rng.uniform(math.log(2700), math.log(8000))))
        wb = kelvin * float(np.exp(rng.normal(0.0, 0.15))) if rng.random() < 0.7 else float(rng.uniform(3500, 6500))
        ambient = float(rng.uniform(0.2, 0.65))
        intensity = float(rng.uniform(0.05, 0.85 - ambient * 0.6))
        specular = float(rng.uniform(0.0, 0.25))
        exposure = float(np.exp(rng.uniform(math.log(0.55), math.log(1.6))))
        exposure = min(exposure, 1.15 / (ambient + intensity + 0.5 * specular))
        return cls(azimuth=float(rng.uniform(-math.pi, math.pi)), elevation=float(rng.uniform(0.2, 1.45)),
                   intensity=intensity, ambient=ambient, specular=specular, kelvin=kelvin,
                   white_balance=float(np.clip(wb, 2000, 12000)), exposure=exposure,
                   bloom=float(rng.uniform(0.05, 0.6)))


@dataclass
class View:
    """A rendered view: BGR image and the segmentation (``-1`` where nothing was drawn)."""
    image: np.ndarray
    seg: np.ndarray                 # int64 H x W: body + ((link + 1) << 24), or -1

    @property
    def body(self) -> np.ndarray:
        return np.where(self.seg >= 0, self.seg & ((1 << LINK_SHIFT) - 1), -1)

    @property
    def link(self) -> np.ndarray:
        """Link index per pixel (-1 the base, -2 nothing)."""
        return np.where(self.seg >= 0, (self.seg >> LINK_SHIFT) - 1, -2)


def seg_value(body: int, link: int) -> int:
    """The segmentation value of ``link`` of ``body``."""
    return int(body) + ((int(link) + 1) << LINK_SHIFT)


def render_view(cid: int, eye, rot: np.ndarray, intr: CameraIntrinsics, lighting: Lighting = Lighting(),
                emitters: dict[int, tuple[float, float, float]] | None = None,
                window: tuple[int, int, int, int] | None = None) -> View:
    """Render the view from ``eye`` with rotation ``rot`` (see the module).
    ``emitters`` maps segmentation values (:func:`seg_value`) of lit parts
    to their linear emission (R, G, B).  With ``window`` (x, y, w, h in
    pixels of the ``intr`` image) only that part of the image is rendered
    (an off-centre frustum), pixel for pixel as the whole view would show it."""
    p = pybullet()
    eye = np.asarray(eye, float)
    view = p.computeViewMatrix(eye.tolist(), (eye + rot[:, 2]).tolist(), (-rot[:, 1]).tolist(),
                               physicsClientId=cid)
    if window is None:
        width, height = intr.width, intr.height
        vfov = math.degrees(2.0 * math.atan(intr.height / (2.0 * intr.fy)))
        proj = p.computeProjectionMatrixFOV(vfov, intr.width / intr.height, NEAR, FAR, physicsClientId=cid)
    else:
        x, y, width, height = (int(v) for v in window)
        proj = p.computeProjectionMatrix(NEAR * (x - intr.cx) / intr.fx, NEAR * (x + width - intr.cx) / intr.fx,
                                         NEAR * (intr.cy - y - height) / intr.fy, NEAR * (intr.cy - y) / intr.fy,
                                         NEAR, FAR, physicsClientId=cid)
    _, _, rgba, _, seg = p.getCameraImage(
        width, height, view, proj, shadow=0, renderer=p.ER_TINY_RENDERER,
        lightDirection=lighting.direction, lightColor=[1.0, 1.0, 1.0], lightAmbientCoeff=lighting.ambient,
        lightDiffuseCoeff=lighting.intensity, lightSpecularCoeff=lighting.specular,
        flags=p.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX, physicsClientId=cid)
    rgb = np.reshape(np.asarray(rgba, dtype=np.uint8), (height, width, 4))[:, :, :3]
    seg = np.reshape(np.asarray(seg, dtype=np.int64), (height, width))
    return View(develop(rgb, seg, lighting, emitters or {}, intr.width), seg)


def develop(rgb: np.ndarray, seg: np.ndarray, lighting: Lighting,
            emitters: dict[int, tuple[float, float, float]], frame_width: int | None = None) -> np.ndarray:
    """Steps 2-5 of the module on a TinyRenderer image (RGB uint8) and its
    segmentation; returns BGR uint8.  ``frame_width``: the width of the
    whole view when this is a window of it (the bloom's size goes by it)."""
    img = rgb.astype(np.float32) * np.float32(1.0 / 255.0)
    img *= kelvin_rgb(lighting.kelvin).astype(np.float32)                  # reflected light: the illuminant
    glow = None
    if emitters:
        keys = np.fromiter(emitters, np.int64)
        lit = np.isin(seg, keys)
        if lit.any():
            colours = np.asarray([emitters[int(k)] for k in keys], np.float32)
            order = np.argsort(keys)
            which = order[np.searchsorted(keys[order], seg[lit])]
            # brightest in the middle of each lens: distance to the lens edge, relative
            dist = cv2.distanceTransform(lit.astype(np.uint8), cv2.DIST_L2, 3)
            ys, xs = np.nonzero(lit)
            depth = dist[ys, xs] / max(float(dist.max()), 1.0)
            emission = colours[which] * (0.75 + 0.5 * np.sqrt(depth))[:, None]
            img[lit] = emission + 0.05 * img[lit]
            glow = np.zeros_like(img)
            glow[lit] = emission
    img *= np.float32(lighting.exposure)
    if glow is not None and lighting.bloom > 0:
        img += lighting.bloom * lighting.exposure * _bloom(glow, frame_width or glow.shape[1])
    img *= (1.0 / kelvin_rgb(lighting.white_balance)).astype(np.float32) * np.float32(
        kelvin_rgb(lighting.white_balance)[1])                              # white balance, green kept
    out = np.clip(img * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(out[:, :, ::-1])


def _bloom(glow: np.ndarray, frame_width: int) -> np.ndarray:
    """Lens glare around emitting pixels: two Gaussians (a tight halo and a
    wide veil), their widths in proportion to the view's width."""
    h, w = glow.shape[:2]
    small = cv2.resize(glow, (max(1, w // 4), max(1, h // 4)), interpolation=cv2.INTER_AREA)
    s = frame_width / 640.0
    halo = cv2.GaussianBlur(small, (0, 0), 0.9 * s)
    veil = cv2.GaussianBlur(small, (0, 0), 4.0 * s)
    return cv2.resize(0.7 * halo + 0.3 * veil, (w, h), interpolation=cv2.INTER_LINEAR)
