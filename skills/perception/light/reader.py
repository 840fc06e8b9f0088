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

from .hog import TowerDetector, crop_window, iou
from .mlp import N_STATES, NO_TOWER, Mlp, crop_features

MODEL_DIR = Path(__file__).with_name("models")
DETECTOR_FILE = "tower_hog_svm.npz"
CLASSIFIER_FILE = "light_mlp.npz"
REPORT_FILE = "training_report.json"


class LightReader:
    def __init__(self, detector: TowerDetector, classifier: Mlp, max_detections: int = 3, reject: float = 0.5,
                 candidates: int = 40):
        self.candidates = candidates  # detector hits the network looks at, strongest first
        self.detector = detector
        self.classifier = classifier
        self.max_detections = max_detections
        self.reject = reject          # "no tower" probability at which a hit is dropped

    @classmethod
    def load(cls, directory: str | Path | None = None, **detector_options) -> "LightReader":
        """The models in ``directory`` (default: the ones shipped in the package).
        ``detector_options`` override the saved detector settings."""
        d = Path(directory) if directory is not None else MODEL_DIR
        det_path, net_path = d / DETECTOR_FILE, d / CLASSIFIER_FILE
        for p in (det_path, net_path):
            if not p.is_file():
                raise UserError(f"model file missing: {p}",
                                hint="train models with 'rll-bt vision train-light --out DIR'")
        try:
            with np.load(det_path) as f:
                vector = f["detector"]
                settings = json.loads(str(f["settings"])) if "settings" in f else {}
            classifier = Mlp.load(net_path)
        except (OSError, ValueError, KeyError) as exc:
            raise UserError(f"cannot read the light models in {d}: {exc}") from None
        reject = float(settings.pop("reject", 0.5))
        settings.update(detector_options)
        return cls(TowerDetector(vector, **settings), classifier, reject=reject)

    def network_output(self, image: np.ndarray, boxes) -> np.ndarray:
        """The network's probabilities (8 states, and "no tower" when it has
        that class) for each tower box (x, y, w, h) of ``image``."""
        n_out = self.classifier.w2.shape[1]
        if len(boxes) == 0:
            return np.zeros((0, n_out))
        x = np.stack([crop_features(crop_window(image, b, self.classifier.size), self.classifier.size)
                      for b in boxes]).astype(np.float64)
        return self.classifier.probabilities(x)

    def classify(self, image: np.ndarray, boxes) -> np.ndarray:
        """Probabilities over the eight states for each tower box (x, y, w, h) of ``image``."""
        p = self.network_output(image, boxes)[:, :N_STATES]
        return p / np.maximum(p.sum(axis=1, keepdims=True), 1e-12)

    def read(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
             tower_height: float | None = None, camera: str = "front") -> list[LightDetection]:
        """Signal towers in a BGR image with their light states, best first.
        Hits the network calls "no tower" are dropped."""
        boxes = self.detector.detect(image, region=region, tower_height=tower_height)[: self.candidates]
        if not self.classifier.verifies:
            probs = self.classify(image, [b.xywh for b in boxes])
            return [LightDetection(box=b.xywh, state=int(p.argmax()), score=b.score,
                                   probabilities=tuple(float(v) for v in p), camera=camera)
                    for b, p in zip(boxes, probs)][: self.max_detections]
        # the detector's box is often too tall (the tower's mount continues its outline):
        # the network looks at shorter, top-anchored variants and keeps the most tower-like
        if not boxes:
            return []
        variants = [refine_box(b.xywh, k) for b in boxes for k in REFINE_HEIGHTS]
        out = self.network_output(image, variants).reshape(len(boxes), len(REFINE_HEIGHTS), -1)
        found = []
        for b, outs, vs in zip(boxes, out, _chunks(variants, len(REFINE_HEIGHTS))):
            best = int(np.argmin(outs[:, NO_TOWER]))
            p = outs[best]
            if p[NO_TOWER] >= self.reject:
                continue
            states = p[:N_STATES] / max(float(p[:N_STATES].sum()), 1e-12)
            if any(iou(vs[best], f.box) > 0.3 for f in found):
                continue
            found.append(LightDetection(box=tuple(int(round(v)) for v in vs[best]), state=int(states.argmax()),
                                        score=b.score, probabilities=tuple(float(v) for v in states),
                                        camera=camera))
        return found[: self.max_detections]


REFINE_HEIGHTS = (1.0, 0.82, 0.68)


def refine_box(box, k: float) -> tuple[float, float, float, float]:
    """``box`` shortened to ``k`` of its height, keeping its top and its centre line."""
    x, y, w, h = (float(v) for v in box)
    return (x + w * (1 - k) / 2, y, w * k, h * k)


def _chunks(items: list, n: int) -> list[list]:
    return [items[i:i + n] for i in range(0, len(items), n)]


def save_detector(path: str | Path, vector: np.ndarray, **settings) -> None:
    """Write a detector vector, its :class:`TowerDetector` settings and the
    reader's ``reject`` level (the network's "no tower" probability at which
    a hit is dropped)."""
    np.savez_compressed(path, detector=np.asarray(vector, np.float32), settings=np.array(json.dumps(settings)))
