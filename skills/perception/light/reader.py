"""The paper's chain: HOG detector -> crop -> network -> light state.

    reader = LightReader.load()                  # the models shipped in the package
    for det in reader.read(image):               # best first
        det.state, det.lights, det.probabilities

``read`` may be restricted to a region (x, y, w, h) of the image and an
expected tower height in pixels, e.g. where the tag pose says the tower must
be (:func:`skills.perception.light.region.tower_region`), which is both
faster and safer.  Boxes are the tower's outline in image pixels.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rll_bt.backend import LightDetection
from rll_bt.errors import UserError

from .hog import TowerDetector, crop_window
from .mlp import Mlp

MODEL_DIR = Path(__file__).with_name("models")
DETECTOR_FILE = "tower_hog_svm.npz"
CLASSIFIER_FILE = "light_mlp.npz"
CHECKER_FILE = "tower_check_mlp.npz"
REPORT_FILE = "training_report.json"


class LightReader:
    """Detector, the tower check (a small network saying whether a hit is
    a tower: optional) and the light network (8 states)."""

    def __init__(self, detector: TowerDetector, classifier: Mlp, checker: Mlp | None = None,
                 max_detections: int = 3, reject: float = 0.5, candidates: int = 40,
                 region_threshold: float | None = None, jitter: bool = True):
        self.jitter = jitter          # read each tower from a few shifted crops and average
        self.detector = detector
        self.classifier = classifier
        self.checker = checker
        self.max_detections = max_detections
        self.reject = reject          # "no tower" probability at which a hit is dropped
        self.candidates = candidates  # detector hits the networks look at, strongest first
        # the detector's threshold inside a tag-given region (a tower is expected there)
        self.region_threshold = detector.threshold if region_threshold is None else region_threshold

    @classmethod
    def load(cls, directory: str | Path | None = None, **detector_options) -> "LightReader":
        """The models in ``directory`` (default: the ones shipped in the package).
        ``detector_options`` override the saved detector settings."""
        d = Path(directory) if directory is not None else MODEL_DIR
        det_path, net_path, check_path = d / DETECTOR_FILE, d / CLASSIFIER_FILE, d / CHECKER_FILE
        for p in (det_path, net_path):
            if not p.is_file():
                raise UserError(f"model file missing: {p}",
                                hint="train models with 'rll-bt vision train-light --out DIR'")
        try:
            with np.load(det_path) as f:
                vector = f["detector"]
                settings = json.loads(str(f["settings"])) if "settings" in f else {}
            classifier = Mlp.load(net_path)
            checker = Mlp.load(check_path) if check_path.is_file() else None
        except (OSError, ValueError, KeyError) as exc:
            raise UserError(f"cannot read the light models in {d}: {exc}") from None
        reject = float(settings.pop("reject", 0.5))
        region_threshold = settings.pop("region_threshold", None)
        settings.update(detector_options)
        if "threshold" in detector_options:
            region_threshold = None
        return cls(TowerDetector(vector, **settings), classifier, checker, reject=reject,
                   region_threshold=region_threshold)

    @staticmethod
    def _run(net: Mlp, image: np.ndarray, boxes) -> np.ndarray:
        if len(boxes) == 0:
            return np.zeros((0, net.w2.shape[1]))
        return net.probabilities(net.features([crop_window(image, b, net.size) for b in boxes]).astype(np.float64))

    def classify(self, image: np.ndarray, boxes) -> np.ndarray:
        """Probabilities over the eight states for each tower box (x, y, w, h) of
        ``image``; with ``jitter``, the geometric mean over the box and its
        :data:`JITTER` variants (a box a pixel off must not change the reading),
        normalised."""
        if not self.jitter or len(boxes) == 0:
            return self._run(self.classifier, image, boxes)
        variants = [jittered(b, j) for b in boxes for j in JITTER]
        p = self._run(self.classifier, image, variants).reshape(len(boxes), len(JITTER), -1)
        logp = np.log(np.clip(p, 1e-12, 1.0)).mean(axis=1)
        q = np.exp(logp - logp.max(axis=1, keepdims=True))
        return q / q.sum(axis=1, keepdims=True)

    def no_tower(self, image: np.ndarray, boxes) -> np.ndarray:
        """The tower check's probability that each box is not a tower (zeros without a check)."""
        if self.checker is None:
            return np.zeros(len(boxes))
        return self._run(self.checker, image, boxes)[:, 1]

    def read(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
             tower_height: float | None = None, camera: str = "front") -> list[LightDetection]:
        """Signal towers in a BGR image with their light states, best first.
        Hits the tower check calls "no tower" are dropped."""
        thr = self.region_threshold if region is not None and tower_height is not None else None
        boxes = self.detector.detect(image, region=region, tower_height=tower_height, threshold=thr)
        boxes = boxes[: self.candidates]
        if not boxes:
            return []
        # the detector's box is often too tall (the tower's mount continues its outline):
        # the check looks at shorter, top-anchored variants and keeps the most tower-like
        heights = REFINE_HEIGHTS if self.checker is not None else (1.0,)
        variants = [refine_box(b.xywh, k) for b in boxes for k in heights]
        p_no = self.no_tower(image, variants).reshape(len(boxes), len(heights))
        picks = choose(_chunks(variants, len(heights)), p_no, self.reject, self.max_detections)
        chosen = [(boxes[i], v) for i, v in picks]
        probs = self.classify(image, [v for _, v in chosen])
        return [LightDetection(box=tuple(int(round(c)) for c in v), state=int(p.argmax()), score=b.score,
                               probabilities=tuple(float(x) for x in p), camera=camera)
                for (b, v), p in zip(chosen, probs)]


REFINE_HEIGHTS = (1.0, 0.82, 0.68)

#: (dx, dy, scale) of the crops a tower is read from: dx of its width, dy of its height
JITTER = ((0.0, 0.0, 1.0), (-0.12, 0.0, 1.0), (0.12, 0.0, 1.0), (0.0, -0.04, 1.0), (0.0, 0.04, 1.0),
          (0.0, 0.0, 0.92), (0.0, 0.0, 1.08))


def jittered(box, j) -> tuple[float, float, float, float]:
    """``box`` shifted by (dx * w, dy * h) and scaled by ``scale`` about its centre."""
    dx, dy, k = j
    x, y, w, h = (float(v) for v in box)
    cx, cy = x + w / 2 + dx * w, y + h / 2 + dy * h
    return (cx - w * k / 2, cy - h * k / 2, w * k, h * k)


def refine_box(box, k: float) -> tuple[float, float, float, float]:
    """``box`` shortened to ``k`` of its height, keeping its top and its centre line."""
    x, y, w, h = (float(v) for v in box)
    return (x + w * (1 - k) / 2, y, w * k, h * k)


def choose(variants, p_no: np.ndarray, reject: float, limit: int, overlap: float = 0.3
           ) -> list[tuple[int, tuple]]:
    """The hits to keep, in order (strongest detector score first): each
    hit's most tower-like variant box, when the check's "no tower"
    probability ``p_no`` (hits x variants) is below ``reject`` and the box
    covers no more than ``overlap`` of a kept box or is covered no more
    (two towers never overlap much; a box on part of a kept tower is a
    duplicate).  Returns (hit index, box), at most ``limit``."""
    out = []
    for i, (vs, p) in enumerate(zip(variants, p_no)):
        best = int(np.argmin(p))
        if p[best] >= reject or any(overlap_of_smaller(vs[best], c) > overlap for _, c in out):
            continue
        out.append((i, vs[best]))
        if len(out) == limit:
            break
    return out


def overlap_of_smaller(a, b) -> float:
    """Intersection of two (x, y, w, h) boxes over the smaller one's area."""
    ix = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    return ix * iy / max(min(a[2] * a[3], b[2] * b[3]), 1e-9)


def _chunks(items: list, n: int) -> list[list]:
    return [items[i:i + n] for i in range(0, len(items), n)]


def save_detector(path: str | Path, vector: np.ndarray, **settings) -> None:
    """Write a detector vector, its :class:`TowerDetector` settings and the
    reader's ``reject`` level (the tower check's "no tower" probability at
    which a hit is dropped) and ``region_threshold``."""
    np.savez_compressed(path, detector=np.asarray(vector, np.float32), settings=np.array(json.dumps(settings)))
