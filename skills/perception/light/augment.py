"""Photometric augmentation of camera frames (BGR uint8 in, BGR uint8 out).

Each call draws, from ``rng``: an exposure (a gain of 0.4-1.8 on linear
light, clipping what it pushes over full scale), brightness offset,
contrast, gamma, a colour cast (per-channel gain, like a white-balance
error), saturation, vignetting, blur (Gaussian up to 2.5 px, defocus or a
short motion streak), sensor noise and JPEG compression (quality 30-95).
The same ``rng`` state gives the same image, whatever ran before in the
process (training is reproducible).  ``strength`` scales all of them (0:
the image unchanged).
"""
from __future__ import annotations

import cv2
import numpy as np


def photometric(img: np.ndarray, rng: np.random.Generator, strength: float = 1.0) -> np.ndarray:
    if strength <= 0:
        return img
    s = strength
    # colour cast, contrast, brightness and gamma are one curve per channel: a lookup table
    exposure = float(np.exp(rng.uniform(np.log(0.4), np.log(1.8)) * min(1.0, s)))
    gain = 1.0 + rng.uniform(-0.18, 0.18, 3) * s
    contrast = 1.0 + rng.uniform(-0.3, 0.3) * s
    mean = float(img.mean()) / 255.0
    offset = rng.uniform(-0.12, 0.12) * s
    gamma = float(np.exp(rng.uniform(-0.3, 0.3) * s))
    v = np.arange(256, dtype=np.float32)[:, None] / 255.0
    lin = np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4) * exposure * gain[None, :]
    lin = np.clip(lin, 0, 1)
    v = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(lin, 1 / 2.4) - 0.055)
    v = np.clip((v - mean) * contrast + mean + offset, 0, 1) ** gamma
    lut = np.clip(v * 255.0 + 0.5, 0, 255).astype(np.uint8)           # 256 x 3
    out = cv2.LUT(img, lut.reshape(256, 1, 3))
    if rng.random() < 0.5:                                             # saturation
        k = float(np.exp(rng.uniform(-0.6, 0.35) * s))
        grey = cv2.cvtColor(cv2.cvtColor(out, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
        out = cv2.addWeighted(out, k, grey, 1.0 - k, 0.0)
    if rng.random() < 0.3 * s:                                         # vignetting
        h, w = out.shape[:2]
        yy, xx = np.ogrid[:h, :w]
        r2 = ((xx - w / 2) / (w / 2)) ** 2 + ((yy - h / 2) / (h / 2)) ** 2
        fall = (1.0 - rng.uniform(0.1, 0.45) * min(1.0, s) * r2 / 2).astype(np.float32)
        out = np.clip(out * fall[:, :, None], 0, 255).astype(np.uint8)
    r = rng.random()
    if r < 0.35 * s:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.3, 2.5) * min(1.0, s))
    elif r < 0.45 * s:                                                 # defocus: a disc
        rad = rng.uniform(0.8, 2.5) * min(1.0, s)
        k = 2 * int(np.ceil(rad)) + 1
        disc = np.zeros((k, k), np.float32)
        cv2.circle(disc, (k // 2, k // 2), int(round(rad)), 1.0, -1)
        out = cv2.filter2D(out, -1, disc / disc.sum())
    elif r < 0.55 * s:                                                 # motion streak
        n = int(rng.integers(2, 5))
        k = np.zeros((n, n), np.float32)
        if rng.random() < 0.5:
            k[n // 2, :] = 1.0 / n
        else:
            k[:, n // 2] = 1.0 / n
        out = cv2.filter2D(out, -1, k)
    if rng.random() < 0.7:                                             # sensor noise
        noise = np.empty(out.shape, np.int16)
        cv2.setRNGSeed(int(rng.integers(2 ** 31)))    # OpenCV's own generator is global: seed it from rng
        cv2.randn(noise, 0, float(rng.uniform(0, 7) * s))
        out = np.clip(out.astype(np.int16) + noise, 0, 255).astype(np.uint8)
    if rng.random() < 0.7 * min(1.0, s):
        q = int(rng.integers(max(30, int(95 - 65 * s)), 96))
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, q])
        if ok:
            out = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out
