"""A HOG detector for the signal tower (Dalal & Triggs, with OpenCV).

The window fits the tower's shape: the three segments and the housing are
about 36 x 147 mm, so the window is 4 cells wide by 14 high with a margin
of roughly one tower width around it.  Training follows OpenCV's recipe:
HOG on grey crops, a linear SVM from ``cv2.ml`` (EPS_SVR, C = 0.01,
P = 0.1), the detector vector ``[w..., -rho]``, then hard negatives (false
detections on tower-free images) added and the SVM trained again.
Detection searches several scales, optionally only inside a region (where
the tag pose says the tower must be).
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

WIN = (24, 72)        # width, height in pixels
BLOCK = (8, 8)
STRIDE = (4, 4)
CELL = (4, 4)
BINS = 9


def make_hog() -> cv2.HOGDescriptor:
    return cv2.HOGDescriptor(WIN, BLOCK, STRIDE, CELL, BINS)


def to_grey(image: np.ndarray) -> np.ndarray:
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def window_features(hog: cv2.HOGDescriptor, crops: list[np.ndarray]) -> np.ndarray:
    """HOG descriptors of crops resized to the window."""
    feats = [hog.compute(cv2.resize(to_grey(c), WIN, interpolation=cv2.INTER_AREA)).ravel()
             for c in crops]
    return np.asarray(feats, dtype=np.float32)


def random_negatives(images: list[np.ndarray], count: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Random window-shaped crops at random scales from tower-free images."""
    out = []
    for _ in range(count):
        img = images[int(rng.integers(len(images)))]
        h, w = img.shape[:2]
        scale = float(rng.uniform(0.6, 3.0))
        cw, ch = int(WIN[0] * scale), int(WIN[1] * scale)
        if cw >= w or ch >= h:
            continue
        x, y = int(rng.integers(0, w - cw)), int(rng.integers(0, h - ch))
        out.append(img[y:y + ch, x:x + cw])
    return out


def train_svm(pos: np.ndarray, neg: np.ndarray, c: float = 0.01) -> np.ndarray:
    """A linear SVM; returns the detector vector [w..., -rho]."""
    svm = cv2.ml.SVM_create()
    svm.setCoef0(0.0)
    svm.setDegree(3)
    svm.setTermCriteria((cv2.TERM_CRITERIA_MAX_ITER + cv2.TERM_CRITERIA_EPS, 1000, 1e-3))
    svm.setGamma(0)
    svm.setKernel(cv2.ml.SVM_LINEAR)
    svm.setNu(0.5)
    svm.setP(0.1)
    svm.setC(c)
    svm.setType(cv2.ml.SVM_EPS_SVR)
    x = np.vstack([pos, neg]).astype(np.float32)
    y = np.concatenate([np.ones(len(pos)), -np.ones(len(neg))]).astype(np.float32)
    svm.train(x, cv2.ml.ROW_SAMPLE, y)
    sv = svm.getSupportVectors()
    rho, _, _ = svm.getDecisionFunction(0)
    return np.append(sv[0].ravel(), -rho).astype(np.float32)


@dataclass
class Box:
    x: int
    y: int
    w: int
    h: int
    score: float


class TowerDetector:
    """Multi-scale sliding-window search with a trained HOG + linear SVM."""

    def __init__(self, detector: np.ndarray, threshold: float = 0.0, scale: float = 1.1,
                 stride: tuple[int, int] = (4, 4), nms_overlap: float = 0.3):
        self.hog = make_hog()
        self.vector = np.asarray(detector, dtype=np.float32)
        if self.vector.size != self.hog.getDescriptorSize() + 1:
            raise ValueError(f"detector has {self.vector.size} values, the window needs "
                             f"{self.hog.getDescriptorSize() + 1}")
        self.hog.setSVMDetector(self.vector)
        self.threshold, self.scale, self.stride, self.nms_overlap = threshold, scale, stride, nms_overlap

    def score(self, crops: list[np.ndarray]) -> np.ndarray:
        feats = window_features(self.hog, crops)
        return feats @ self.vector[:-1] + self.vector[-1]

    def detect(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
               max_height: int | None = None) -> list[Box]:
        """Towers in ``image`` (optionally only inside ``region`` = x, y, w, h), best first."""
        grey = to_grey(image)
        ox = oy = 0
        if region is not None:
            x, y, w, h = (int(v) for v in region)
            x0, y0 = max(x, 0), max(y, 0)
            x1, y1 = min(x + w, grey.shape[1]), min(y + h, grey.shape[0])
            if x1 - x0 < WIN[0] or y1 - y0 < WIN[1]:
                return []
            grey, ox, oy = grey[y0:y1, x0:x1], x0, y0
        if grey.shape[0] < WIN[1] or grey.shape[1] < WIN[0]:
            return []
        rects, weights = self.hog.detectMultiScale(grey, hitThreshold=self.threshold,
                                                   winStride=self.stride, padding=(0, 0),
                                                   scale=self.scale, groupThreshold=0)
        boxes = [Box(int(r[0]) + ox, int(r[1]) + oy, int(r[2]), int(r[3]), float(s))
                 for r, s in zip(rects, np.ravel(weights))]
        if max_height is not None:
            boxes = [b for b in boxes if b.h <= max_height]
        return non_max_suppression(boxes, self.nms_overlap)


def non_max_suppression(boxes: list[Box], overlap: float) -> list[Box]:
    kept: list[Box] = []
    for b in sorted(boxes, key=lambda b: -b.score):
        if all(_iou(b, k) < overlap for k in kept):
            kept.append(b)
    return kept


def _iou(a: Box, b: Box) -> float:
    ix = max(0, min(a.x + a.w, b.x + b.w) - max(a.x, b.x))
    iy = max(0, min(a.y + a.h, b.y + b.h) - max(a.y, b.y))
    inter = ix * iy
    return inter / float(a.w * a.h + b.w * b.h - inter) if inter else 0.0
