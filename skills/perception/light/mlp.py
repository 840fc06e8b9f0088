"""A small feed-forward network over signal-tower crops: the classifier of
the paper's chain.  One tanh hidden layer, softmax over the eight light
states (green 1, yellow 2, red 4), cross-entropy with weight decay,
trained with scaled conjugate gradient on a flat parameter vector.  The
same kind of network with two outputs (tower, no tower) is the tower
check that looks at the detector's hits first.

Input (:func:`crop_features`): the tower's crop cut at ``size`` (w, h;
8 x 32 pixels, the tower's shape) in BGR, described by

- ``pixels``: the crop reduced to 6 x 24, as floats in [0, 1] minus 0.5;
- ``rich``: those pixels, plus each row's brightest value per channel (a
  lit lens is bright across its middle wherever the box sits), plus a HOG
  of the grey crop (4-pixel cells: the outline);
- ``tower`` (the default): ``rich`` plus, per row, its brightness against
  the crop's brightest (exposure cancels), its saturation, and its mean
  hue as a direction weighted by saturation and brightness (a lit lens is
  bright and saturated at its rim even where its core clips to white; a
  milky unlit lens is bright but pale).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from .scg import scg

N_STATES = 8
NO_TOWER = 8          # the label of "no tower" crops in the training material
DEFAULT_SIZE = (8, 32)
PIXELS = (6, 24)
KINDS = ("pixels", "rich", "tower")


@lru_cache(maxsize=1)
def _crop_hog() -> cv2.HOGDescriptor:
    return cv2.HOGDescriptor((8, 32), (8, 8), (4, 4), (4, 4), 9)


def crop_features(crop: np.ndarray, size: tuple[int, int] = DEFAULT_SIZE, kind: str = "tower") -> np.ndarray:
    """A BGR crop to the network's input vector (see the module)."""
    if crop.shape[1] != size[0] or crop.shape[0] != size[1]:
        crop = cv2.resize(crop, size, interpolation=cv2.INTER_AREA)
    small = crop if tuple(size) == PIXELS else cv2.resize(crop, PIXELS, interpolation=cv2.INTER_AREA)
    px = small.astype(np.float32).ravel() / 255.0 - 0.5
    if kind == "pixels":
        return px
    if kind not in KINDS:
        raise ValueError(f"unknown feature kind {kind!r} (known: {', '.join(KINDS)})")
    rows = crop.max(axis=1).astype(np.float32).ravel() / 255.0 - 0.5
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY)
    if grey.shape != (32, 8):
        grey = cv2.resize(grey, (8, 32), interpolation=cv2.INTER_AREA)
    rich = [px, rows, _crop_hog().compute(grey).ravel()]
    if kind == "tower":
        rich.append(_row_colour(crop))
    return np.concatenate(rich)


def batch_features(crops, kind: str = "tower") -> np.ndarray:
    """:func:`crop_features` of many BGR crops of :data:`DEFAULT_SIZE` at once
    (the per-pixel and per-row parts on all of them together: a reader's
    tens of crops cost a third of the time)."""
    w, h = DEFAULT_SIZE
    n = len(crops)
    stack = np.stack(crops)                                       # n x h x w x 3
    tall = stack.reshape(n * h, w, 3)
    px = np.stack([cv2.resize(c, PIXELS, interpolation=cv2.INTER_AREA) for c in crops])
    px = px.reshape(n, -1).astype(np.float32) / 255.0 - 0.5
    rows = stack.max(axis=2).reshape(n, -1).astype(np.float32) / 255.0 - 0.5
    grey = cv2.cvtColor(tall, cv2.COLOR_BGR2GRAY).reshape(n, h, w)
    hog = _crop_hog()
    parts = [px, rows, np.stack([hog.compute(g).ravel() for g in grey])]
    if kind == "tower":
        hsv = cv2.cvtColor(tall, cv2.COLOR_BGR2HSV_FULL).astype(np.float32).reshape(n, h, w, 3)
        hue, sat, val = hsv[..., 0] * (2 * np.pi / 256.0), hsv[..., 1] / 255.0, hsv[..., 2] / 255.0
        flat = val.reshape(n, -1)
        pos = (flat.shape[1] - 1) * 0.98
        lo = int(pos)
        hi = min(lo + 1, flat.shape[1] - 1)
        part = np.partition(flat, (lo, hi), axis=1)
        top = np.maximum(part[:, lo] + (part[:, hi] - part[:, lo]) * (pos - lo), 0.05)[:, None]
        wgt = sat * val
        parts.append(np.concatenate([np.minimum(val.mean(axis=2) / top, 1.5) - 0.5, sat.mean(axis=2) - 0.5,
                                     (wgt * np.cos(hue)).mean(axis=2), (wgt * np.sin(hue)).mean(axis=2)],
                                    axis=1).astype(np.float32))
    return np.concatenate(parts, axis=1)


def _percentile98(v: np.ndarray) -> float:
    """``np.percentile(v, 98)`` (linear interpolation) by a partial sort: a tenth of its time."""
    a = v.ravel()
    pos = (a.size - 1) * 0.98
    lo = int(pos)
    hi = min(lo + 1, a.size - 1)
    part = np.partition(a, (lo, hi))
    return float(part[lo] + (part[hi] - part[lo]) * (pos - lo))


def _row_colour(crop: np.ndarray) -> np.ndarray:
    """Per row of a BGR crop: brightness over the crop's brightest, saturation,
    and the hue direction (cos, sin) weighted by saturation and brightness."""
    hsv = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV_FULL).astype(np.float32)
    h, s, v = hsv[:, :, 0] * (2 * np.pi / 256.0), hsv[:, :, 1] / 255.0, hsv[:, :, 2] / 255.0
    top = max(_percentile98(v), 0.05)
    w = s * v
    return np.concatenate([np.minimum(v.mean(axis=1) / top, 1.5) - 0.5, s.mean(axis=1) - 0.5,
                           (w * np.cos(h)).mean(axis=1), (w * np.sin(h)).mean(axis=1)]).astype(np.float32)


def geometric_mean(p: np.ndarray, axis: int) -> np.ndarray:
    """The normalised geometric mean of probability rows ``p`` along
    ``axis`` (the last axis holds the classes): what several readings of
    one crop, or several networks, agree on."""
    logp = np.log(np.clip(p, 1e-12, 1.0)).mean(axis=axis)
    q = np.exp(logp - logp.max(axis=-1, keepdims=True))
    return q / q.sum(axis=-1, keepdims=True)


@dataclass
class Mlp:
    w1: np.ndarray      # (n_in, n_hidden)
    b1: np.ndarray
    w2: np.ndarray      # (n_hidden, 8)
    b2: np.ndarray
    size: tuple[int, int] = DEFAULT_SIZE
    kind: str = "tower"  # the input features (:func:`crop_features`)

    @classmethod
    def create(cls, n_in: int, n_hidden: int, size=DEFAULT_SIZE, seed: int = 0,
               n_out: int = N_STATES, kind: str = "tower") -> Mlp:
        rng = np.random.default_rng(seed)
        return cls(rng.normal(0, 1 / np.sqrt(n_in), (n_in, n_hidden)), np.zeros(n_hidden),
                   rng.normal(0, 1 / np.sqrt(n_hidden), (n_hidden, n_out)), np.zeros(n_out),
                   tuple(size), kind)

    def features(self, crops) -> np.ndarray:
        """Input rows of BGR crops (any size; cut at ``size``)."""
        if len(crops) == 0:
            return np.zeros((0, self.w1.shape[0]), np.float32)
        if self.kind in ("rich", "tower") and tuple(self.size) == DEFAULT_SIZE and all(
                c.shape == (DEFAULT_SIZE[1], DEFAULT_SIZE[0], 3) for c in crops):
            return batch_features(crops, self.kind)
        return np.stack([crop_features(c, self.size, self.kind) for c in crops])


    # -- flat parameter vector for the optimiser ---------------------------
    def _shapes(self):
        return [self.w1.shape, self.b1.shape, self.w2.shape, self.b2.shape]

    def get(self) -> np.ndarray:
        return np.concatenate([a.ravel() for a in (self.w1, self.b1, self.w2, self.b2)])

    def set(self, theta: np.ndarray) -> None:
        out, i = [], 0
        for shape in self._shapes():
            n = int(np.prod(shape))
            out.append(theta[i:i + n].reshape(shape))
            i += n
        self.w1, self.b1, self.w2, self.b2 = out

    # -- forward / loss ----------------------------------------------------
    def probabilities(self, x: np.ndarray) -> np.ndarray:
        h = np.tanh(x @ self.w1 + self.b1)
        z = h @ self.w2 + self.b2
        z -= z.max(axis=1, keepdims=True)
        e = np.exp(z)
        return e / e.sum(axis=1, keepdims=True)

    def predict(self, x: np.ndarray) -> np.ndarray:
        return self.probabilities(x).argmax(axis=1)

    @property
    def n_out(self) -> int:
        return self.w2.shape[1]

    def loss_and_grad(self, theta: np.ndarray, x: np.ndarray, y: np.ndarray, decay: float):
        """Loss and gradient at ``theta``; the products run in ``x``'s precision
        (float32 during training: twice as fast), the sums in float64."""
        self.set(theta)
        n = len(x)
        w1 = self.w1.astype(x.dtype, copy=False)
        h = np.tanh((x @ w1).astype(np.float64) + self.b1)
        z = h @ self.w2 + self.b2
        z -= z.max(axis=1, keepdims=True)
        e = np.exp(z)
        prob = e / e.sum(axis=1, keepdims=True)
        loss = -np.log(prob[np.arange(n), y] + 1e-12).mean()
        loss += 0.5 * decay * (np.sum(self.w1 ** 2) + np.sum(self.w2 ** 2))
        dz = prob
        dz[np.arange(n), y] -= 1.0
        dz /= n
        gw2 = h.T @ dz + decay * self.w2
        gb2 = dz.sum(axis=0)
        dh = (dz @ self.w2.T) * (1.0 - h ** 2)
        gw1 = (x.T @ dh.astype(x.dtype)).astype(np.float64) + decay * self.w1
        gb1 = dh.sum(axis=0)
        return float(loss), np.concatenate([gw1.ravel(), gb1, gw2.ravel(), gb2])

    def train(self, x: np.ndarray, y: np.ndarray, max_iter: int = 300, decay: float = 1e-4,
              callback=None):
        """Full-batch training with scaled conjugate gradient."""
        x = np.asarray(x, dtype=np.float32)
        y = np.asarray(y, dtype=np.int64)
        cache = {}

        def both(theta):
            key = theta.tobytes()
            if key not in cache:
                cache.clear()
                cache[key] = self.loss_and_grad(theta, x, y, decay)
            return cache[key]

        res = scg(lambda t: both(t)[0], lambda t: both(t)[1], self.get(), max_iter=max_iter,
                  callback=callback)
        self.set(res.x)
        return res

    # -- persistence -------------------------------------------------------
    def save(self, path) -> None:
        np.savez_compressed(path, w1=self.w1.astype(np.float32), b1=self.b1.astype(np.float32),
                            w2=self.w2.astype(np.float32), b2=self.b2.astype(np.float32),
                            size=np.array(self.size), kind=np.array(self.kind))

    @classmethod
    def load(cls, path) -> Mlp:
        with np.load(path) as d:
            kind = str(d["kind"]) if "kind" in d else "pixels"
            return cls(d["w1"].astype(np.float64), d["b1"].astype(np.float64),
                       d["w2"].astype(np.float64), d["b2"].astype(np.float64),
                       tuple(int(v) for v in d["size"]), kind)


@dataclass
class Ensemble:
    """Networks of one input kind trained from different starts, read
    together: the normalised geometric mean of their probabilities.  One network's quirks (a lit
    lens it learnt from a few crops) are outvoted; a crop they disagree on
    gets a flat distribution.  Stored as one file of stacked weights."""
    members: list[Mlp]

    @property
    def size(self) -> tuple[int, int]:
        return self.members[0].size

    @property
    def kind(self) -> str:
        return self.members[0].kind

    @property
    def n_out(self) -> int:
        return self.members[0].n_out

    def features(self, crops) -> np.ndarray:
        return self.members[0].features(crops)

    def probabilities(self, x: np.ndarray) -> np.ndarray:
        return geometric_mean(np.stack([m.probabilities(x) for m in self.members]), axis=0)

    def predict(self, x: np.ndarray) -> np.ndarray:
        return self.probabilities(x).argmax(axis=1)

    def save(self, path) -> None:
        m0 = self.members[0]
        stack = {k: np.stack([getattr(m, k) for m in self.members]).astype(np.float32)
                 for k in ("w1", "b1", "w2", "b2")}
        np.savez_compressed(path, **stack, size=np.array(m0.size), kind=np.array(m0.kind))

    @classmethod
    def load(cls, path) -> Ensemble:
        """An ensemble file, or a single network's file (an ensemble of one)."""
        with np.load(path) as d:
            kind = str(d["kind"]) if "kind" in d else "pixels"
            size = tuple(int(v) for v in d["size"])
            w1, b1, w2, b2 = (d[k].astype(np.float64) for k in ("w1", "b1", "w2", "b2"))
        if w1.ndim == 2:
            w1, b1, w2, b2 = w1[None], b1[None], w2[None], b2[None]
        return cls([Mlp(w1[i], b1[i], w2[i], b2[i], size, kind) for i in range(len(w1))])
