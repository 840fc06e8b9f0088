"""A HOG detector for the signal tower (Dalal & Triggs, with OpenCV).

The window fits the tower's shape: the tower (36 x 147 mm: three 34 mm
segments and the housing) fills the middle half of a 16 x 48 pixel window
across and 33 of its 48 pixels up (a margin of one cell or more of
background on every side, where the silhouette's edges are).  Cells are
4 x 4 pixels, blocks 8 x 8, so a tower 8 pixels wide is two cells across.

Training follows OpenCV's recipe: HOG on grey crops, a linear SVM from
``cv2.ml`` (EPS_SVR, C = 0.01, P = 0.1), the detector vector
``[w..., -rho]``, then hard negatives (false detections on tower-free
images) added and the SVM trained again.  Detection runs the window over an
image pyramid (also enlarged, for towers narrower than the window's),
optionally only inside a region and around an expected tower height (where
the tag pose says the tower must be), then keeps the best of overlapping
hits.  Boxes are the tower's outline (x, y, w, h) in image pixels.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

WIN = (16, 48)        # width, height in pixels
BLOCK = (8, 8)
STRIDE = (4, 4)
CELL = (4, 4)
BINS = 9
TOWER_W = 8.0         # the tower's width in the window, pixels
TOWER_H = 33.0        # the tower's height in the window (147 / 36 * 8)


def make_hog(nlevels: int = 64) -> cv2.HOGDescriptor:
    """The descriptor; ``nlevels`` caps the pyramid levels ``detectMultiScale`` searches."""
    return cv2.HOGDescriptor(WIN, BLOCK, STRIDE, CELL, BINS, 1, -1.0, cv2.HOGDescriptor_L2Hys, 0.2, False,
                             nlevels, False)


def to_grey(image: np.ndarray) -> np.ndarray:
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


def window_for_tower(box) -> tuple[float, float, float, float]:
    """The detection window (x, y, w, h) that holds a tower box as the
    training positives do; its scale is set by the tower's height."""
    x, y, w, h = (float(v) for v in box)
    wh = h * WIN[1] / TOWER_H
    ww = wh * WIN[0] / WIN[1]
    return (x + w / 2 - ww / 2, y + h / 2 - wh / 2, ww, wh)


def tower_in_window(x: float, y: float, ww: float, wh: float) -> tuple[float, float, float, float]:
    """The tower box inside a detection window (the inverse of :func:`window_for_tower`)."""
    w, h = ww * TOWER_W / WIN[0], wh * TOWER_H / WIN[1]
    return (x + (ww - w) / 2, y + (wh - h) / 2, w, h)


def crop_window(image: np.ndarray, win, size: tuple[int, int] = WIN) -> np.ndarray:
    """The box ``win`` (x, y, w, h; may leave the image, whose border is then
    replicated) resized to ``size``."""
    x, y, w, h = win
    x0, y0 = int(round(x)), int(round(y))
    x1, y1 = max(x0 + 1, int(round(x + w))), max(y0 + 1, int(round(y + h)))
    H, W = image.shape[:2]
    pad = max(0, -x0, -y0, x1 - W, y1 - H)
    if pad:
        lo_x, lo_y = max(0, x0), max(0, y0)
        sub = image[lo_y:min(H, y1), lo_x:min(W, x1)]
        if sub.size == 0:
            sub = np.zeros((1, 1) + image.shape[2:], image.dtype)
        sub = cv2.copyMakeBorder(sub, lo_y - y0, max(0, y1 - H), lo_x - x0, max(0, x1 - W),
                                 cv2.BORDER_REPLICATE)
    else:
        sub = image[y0:y1, x0:x1]
    shrink = sub.shape[1] > size[0]
    return cv2.resize(sub, size, interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)


def window_features(hog: cv2.HOGDescriptor, crops: list[np.ndarray]) -> np.ndarray:
    """HOG descriptors of crops (resized to the window when they are not)."""
    feats = []
    for c in crops:
        g = to_grey(c)
        if g.shape[1] != WIN[0] or g.shape[0] != WIN[1]:
            g = cv2.resize(g, WIN, interpolation=cv2.INTER_AREA)
        feats.append(hog.compute(g).ravel())
    if not feats:
        return np.zeros((0, hog.getDescriptorSize()), np.float32)
    return np.asarray(feats, dtype=np.float32)


def random_negatives(images: list[np.ndarray], count: int, rng: np.random.Generator,
                     avoid: list[list[tuple]] | None = None) -> list[np.ndarray]:
    """Random window-shaped crops at random scales from images, away from
    the tower boxes in ``avoid`` (one list per image)."""
    out = []
    tries = 0
    while len(out) < count and tries < count * 5:
        tries += 1
        i = int(rng.integers(len(images)))
        img = images[i]
        h, w = img.shape[:2]
        wh = float(np.exp(rng.uniform(np.log(30), np.log(min(h, 3.5 * w) * 0.9))))
        ww = wh * WIN[0] / WIN[1]
        if ww >= w or wh >= h:
            continue
        x, y = float(rng.uniform(0, w - ww)), float(rng.uniform(0, h - wh))
        tb = tower_in_window(x, y, ww, wh)
        if avoid is not None and any(iou(tb, b) > 0.2 for b in avoid[i]):
            continue
        out.append(crop_window(img, (x, y, ww, wh)))
    return out


def train_svm(pos: np.ndarray, neg: np.ndarray, c: float = 0.01) -> np.ndarray:
    """A linear SVM by OpenCV's recipe; returns the detector vector [w..., -rho]."""
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
    support: int = 1          # raw hits (positions and scales) behind this box

    @property
    def xywh(self) -> tuple[int, int, int, int]:
        return (self.x, self.y, self.w, self.h)


class TowerDetector:
    """Sliding-window search with a trained HOG + linear SVM.

    ``threshold`` is the SVM score a window needs; ``min_support`` the
    number of raw hits (neighbouring positions or scales) a tower needs,
    which drops isolated hits on clutter; ``max_upscale`` how far a frame
    is enlarged for towers narrower than the window's 8 pixels.
    """

    def __init__(self, detector: np.ndarray, threshold: float = 0.0, scale_step: float = 1.15,
                 stride: tuple[int, int] = (4, 4), nms_overlap: float = 0.3, min_support: int = 1,
                 max_upscale: float = 1.1, max_tower_fraction: float = 0.6):
        self.hog = make_hog()
        self.vector = np.asarray(detector, dtype=np.float32).ravel()
        if self.vector.size != self.hog.getDescriptorSize() + 1:
            raise ValueError(f"detector has {self.vector.size} values, the window needs "
                             f"{self.hog.getDescriptorSize() + 1}")
        self.hog.setSVMDetector(self.vector)
        self.threshold, self.scale_step, self.stride = threshold, scale_step, stride
        self.nms_overlap, self.min_support, self.max_upscale = nms_overlap, min_support, max_upscale
        self.max_tower_fraction = max_tower_fraction
        self._by_levels: dict[int, cv2.HOGDescriptor] = {}

    def _hog_with_levels(self, n: int) -> cv2.HOGDescriptor:
        hog = self._by_levels.get(n)
        if hog is None:
            hog = self._by_levels[n] = make_hog(n)
            hog.setSVMDetector(self.vector)
        return hog

    def score(self, crops: list[np.ndarray]) -> np.ndarray:
        """SVM scores of window crops."""
        feats = window_features(self.hog, crops)
        return feats @ self.vector[:-1] + self.vector[-1]

    def levels(self, width: int, height: int, tower_height: float | None = None) -> list[float]:
        """Pyramid scales (image size factors) to search, largest first."""
        if tower_height is not None and tower_height > 0:
            s = TOWER_H / float(tower_height)
            hi, lo = min(s * 1.3, 4.0), s / 1.3
        else:
            hi, lo = self.max_upscale, TOWER_H / (self.max_tower_fraction * height)
        lo = max(lo, WIN[0] / width, WIN[1] / height)
        out, s = [], hi
        while s >= lo - 1e-9:
            out.append(s)
            s /= self.scale_step
        return out

    def raw_hits(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
                 tower_height: float | None = None, threshold: float | None = None,
                 max_hits: int = 400) -> tuple[np.ndarray, np.ndarray]:
        """Every window over ``threshold``, not merged: (N x 4 tower boxes in
        image pixels, N scores), strongest first, at most ``max_hits``."""
        grey = to_grey(image)
        ox = oy = 0
        if region is not None:
            x, y, w, h = (int(round(v)) for v in region)
            x0, y0 = max(x, 0), max(y, 0)
            x1, y1 = min(x + w, grey.shape[1]), min(y + h, grey.shape[0])
            if x1 <= x0 or y1 <= y0:
                return np.zeros((0, 4), np.float32), np.zeros(0, np.float32)
            grey, ox, oy = grey[y0:y1, x0:x1], x0, y0
        thr = self.threshold if threshold is None else threshold
        gh, gw = grey.shape[:2]
        levels = self.levels(gw, gh, tower_height)
        empty = (np.zeros((0, 4), np.float32), np.zeros(0, np.float32))
        if not levels:
            return empty
        s0 = levels[0]
        size = (int(round(gw * s0)), int(round(gh * s0)))
        if size[0] < WIN[0] or size[1] < WIN[1]:
            return empty
        top = grey if abs(s0 - 1.0) < 1e-6 else cv2.resize(
            grey, size, interpolation=cv2.INTER_AREA if s0 < 1 else cv2.INTER_LINEAR)
        # OpenCV's own pyramid (parallel): the levels below the largest, at most len(levels)
        hog = self._hog_with_levels(len(levels))
        rects, weights = hog.detectMultiScale(top, hitThreshold=thr, winStride=self.stride, padding=(0, 0),
                                              scale=self.scale_step, groupThreshold=0)
        if len(rects) == 0:
            return empty
        r = np.asarray(rects, np.float32).reshape(-1, 4) / np.float32(s0)
        bw, bh = r[:, 2] * TOWER_W / WIN[0], r[:, 3] * TOWER_H / WIN[1]
        b = np.column_stack([r[:, 0] + (r[:, 2] - bw) / 2 + ox, r[:, 1] + (r[:, 3] - bh) / 2 + oy, bw, bh])
        sc = np.ravel(weights).astype(np.float32)
        # OpenCV's levels run in parallel and hand their hits over in any order: ties of score
        # go by position, so the same image always gives the same hits (training is reproducible)
        order = np.lexsort((b[:, 3], b[:, 2], b[:, 1], b[:, 0], -sc))[:max_hits]
        return b[order], sc[order]

    def detect(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
               tower_height: float | None = None, threshold: float | None = None) -> list[Box]:
        """Towers in ``image`` (optionally only inside ``region`` = x, y, w, h
        and around an expected ``tower_height`` in pixels), best first;
        ``threshold`` overrides the detector's."""
        thr = self.threshold if threshold is None else threshold
        boxes, scores = self.raw_hits(image, region, tower_height, threshold=thr)
        return select(boxes, scores, thr, self.min_support, self.nms_overlap)


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of every box of ``a`` (N x 4, x y w h) with every box of ``b`` (M x 4)."""
    ax0, ay0, ax1, ay1 = a[:, 0], a[:, 1], a[:, 0] + a[:, 2], a[:, 1] + a[:, 3]
    bx0, by0, bx1, by1 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    ix = np.clip(np.minimum(ax1[:, None], bx1[None]) - np.maximum(ax0[:, None], bx0[None]), 0, None)
    iy = np.clip(np.minimum(ay1[:, None], by1[None]) - np.maximum(ay0[:, None], by0[None]), 0, None)
    inter = ix * iy
    union = (a[:, 2] * a[:, 3])[:, None] + (b[:, 2] * b[:, 3])[None] - inter
    return inter / np.maximum(union, 1e-9)


def select(boxes: np.ndarray, scores: np.ndarray, threshold: float, min_support: int = 1,
           overlap: float = 0.3) -> list[Box]:
    """Non-maximum suppression of raw hits at ``threshold``: the strongest of
    every group overlapping by ``overlap`` or more, kept when at least
    ``min_support`` hits (itself included) overlap it by half or more; its
    box is the score-weighted mean of those hits."""
    keep = scores >= threshold
    b, s = boxes[keep], scores[keep]
    if len(s) == 0:
        return []
    order = np.argsort(-s, kind="stable")
    b, s = b[order], s[order]
    m = iou_matrix(b, b)
    alive = np.ones(len(s), bool)
    out = []
    for i in range(len(s)):
        if not alive[i]:
            continue
        alive &= m[i] < overlap
        group = m[i] >= 0.5
        support = int(group.sum())
        if support >= min_support:
            # the box is the score-weighted mean of its group: steadier in scale than the best hit alone
            wts = np.exp((s[group] - s[i]) / 0.1)
            x, y, w, h = (b[group] * wts[:, None]).sum(axis=0) / wts.sum()
            out.append(Box(int(round(x)), int(round(y)), max(1, int(round(w))), max(1, int(round(h))),
                           float(s[i]), support))
    return out


def non_max_suppression(boxes: list[Box], overlap: float) -> list[Box]:
    """Greedy non-maximum suppression of :class:`Box` objects, best first."""
    if not boxes:
        return []
    arr = np.array([b.xywh for b in boxes], np.float32)
    sc = np.array([b.score for b in boxes], np.float32)
    return select(arr, sc, -np.inf, 1, overlap)


def iou(a, b) -> float:
    """Intersection over union of two (x, y, w, h) boxes."""
    ax, ay, aw, ah = a[:4]
    bx, by, bw, bh = b[:4]
    ix = max(0.0, min(ax + aw, bx + bw) - max(ax, bx))
    iy = max(0.0, min(ay + ah, by + bh) - max(ay, by))
    inter = ix * iy
    union = aw * ah + bw * bh - inter
    return inter / union if inter > 0 and union > 0 else 0.0
