"""Photometric augmentation of camera frames (BGR uint8 in, BGR uint8 out).

Each call draws, from ``rng``: brightness offset, contrast, gamma, a colour
cast (per-channel gain, like a white-balance error), saturation, vignetting,
blur (Gaussian or a short motion streak), sensor noise and JPEG
compression.  The same ``rng`` state gives the same image, whatever ran
before in the process (training is reproducible).  ``strength`` scales all of them (0: the image unchanged).
"""
from __future__ import annotations

import cv2
import numpy as np


def photometric(img: np.ndarray, rng: np.random.Generator, strength: float = 1.0) -> np.ndarray:
    if strength <= 0:
        return img
    s = strength
    # colour cast, contrast, brightness and gamma are one curve per channel: a lookup table
    gain = 1.0 + rng.uniform(-0.18, 0.18, 3) * s
    contrast = 1.0 + rng.uniform(-0.35, 0.35) * s
    mean = float(img.mean()) / 255.0
    offset = rng.uniform(-0.2, 0.2) * s
    gamma = float(np.exp(rng.uniform(-0.4, 0.4) * s))
    v = np.arange(256, dtype=np.float32)[:, None] / 255.0 * gain[None, :]
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
    if r < 0.3 * s:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.3, 1.3) * s)
    elif r < 0.4 * s:                                                  # motion streak
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
    if rng.random() < 0.6 * min(1.0, s):
        q = int(rng.integers(max(25, int(95 - 60 * s)), 96))
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, q])
        if ok:
            out = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out
