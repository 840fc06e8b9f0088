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
from threadpoolctl import ThreadpoolController

from rll_bt.backend import LightDetection
from rll_bt.errors import UserError

from .hog import TOWER_H, TOWER_W, TowerDetector, crop_window
from .mlp import Ensemble, Mlp, geometric_mean

MODEL_DIR = Path(__file__).with_name("models")
DETECTOR_FILE = "tower_hog_svm.npz"
CLASSIFIER_FILE = "light_mlp.npz"
CHECKER_FILE = "tower_check_mlp.npz"
REPORT_FILE = "training_report.json"


class LightReader:
    """Detector, the tower check (a small network saying whether a hit is
    a tower: optional) and the light network (8 states)."""

    def __init__(self, detector: TowerDetector, classifier: Mlp | Ensemble, checker: Mlp | Ensemble | None = None,
                 max_detections: int = 3, reject: float = 0.5, candidates: int = 40,
                 region_threshold: float | None = None, jitter: bool = True,
                 snap: float | None = 0.15, min_confidence: float = 0.75,
                 region_reject: float | None = None):
        self.jitter = jitter          # read each tower from a few shifted crops and average
        # with an expected tower height (a tag-given region): how far (a fraction) a box's
        # height may be off it; boxes of that height anchored at the hit's top, middle and
        # bottom are offered to the tower check too.  None: no snapping
        self.snap = snap
        # a tower whose most probable state has less than this probability is not reported:
        # an unsure reading (a lens half lit by its neighbour's glow, a tinted hall) is left
        # to the next frame rather than risked
        self.min_confidence = min_confidence
        self.detector = detector
        self.classifier = classifier
        self.checker = checker
        self.max_detections = max_detections
        self.reject = reject          # "no tower" probability at which a hit is dropped
        self.candidates = candidates  # detector hits the networks look at, strongest first
        # the detector's threshold inside a tag-given region (a tower is expected there)
        self.region_threshold = detector.threshold if region_threshold is None else region_threshold
        # the check's "no tower" level there
        self.region_reject = reject if region_reject is None else region_reject

    @classmethod
    def load(cls, directory: str | Path | None = None, **detector_options) -> LightReader:
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
            classifier = Ensemble.load(net_path)
            checker = Ensemble.load(check_path) if check_path.is_file() else None
        except (OSError, ValueError, KeyError) as exc:
            raise UserError(f"cannot read the light models in {d}: {exc}") from None
        reject = float(settings.pop("reject", 0.5))
        region_threshold = settings.pop("region_threshold", None)
        region_reject = settings.pop("region_reject", None)
        settings.update(detector_options)
        if "threshold" in detector_options:
            region_threshold = None
        return cls(TowerDetector(vector, **settings), classifier, checker, reject=reject,
                   region_threshold=region_threshold, region_reject=region_reject)

    @staticmethod
    def _run(net: Mlp | Ensemble, image: np.ndarray, boxes) -> np.ndarray:
        if len(boxes) == 0:
            return np.zeros((0, net.n_out))
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
        return geometric_mean(p, axis=1)

    def no_tower(self, image: np.ndarray, boxes) -> np.ndarray:
        """The tower check's probability that each box is not a tower (zeros without a check)."""
        if self.checker is None:
            return np.zeros(len(boxes))
        return self._run(self.checker, image, boxes)[:, 1]

    def check(self, image: np.ndarray, boxes, tower_height: float | None = None
              ) -> tuple[list[list[tuple]], np.ndarray]:
        """The box variants of each detector hit (x, y, w, h) and the tower
        check's "no tower" probability of each (hits x variants).

        The detector's box is often too tall (the tower's mount continues its
        outline): the check looks at shorter, top-anchored variants too
        (:data:`REFINE_HEIGHTS`).  With an expected ``tower_height`` (from a
        tag) and ``snap``, boxes of that height anchored at the hit's top,
        middle and bottom are offered as well, and a variant whose height is
        more than ``snap`` off it counts as no tower: the tag gives the
        height to a few per cent, a box far off it is misplaced and would be
        read shifted."""
        heights = REFINE_HEIGHTS if self.checker is not None else (1.0,)
        variants = [[refine_box(b, k) for k in heights] for b in boxes]
        if self.checker is None or not variants:
            return variants, np.zeros((len(variants), len(heights)))
        snap = bool(tower_height) and self.snap is not None
        if snap:
            variants = [vs + snapped(b, tower_height) for vs, b in zip(variants, boxes)]
        flat = [v for vs in variants for v in vs]
        p_no = np.ones(len(flat))
        # only variants of about the tag's height are looked at; the others count as no tower
        fits = np.array([not snap or abs(v[3] / tower_height - 1.0) <= self.snap for v in flat])
        p_no[fits] = self.no_tower(image, [v for v, ok in zip(flat, fits) if ok])
        return variants, p_no.reshape(len(variants), -1)

    def read(self, image: np.ndarray, region: tuple[int, int, int, int] | None = None,
             tower_height: float | None = None, camera: str = "front") -> list[LightDetection]:
        """Signal towers in a BGR image with their light states, best first.
        Hits the tower check calls "no tower" are dropped, and so are towers
        read with less than ``min_confidence``.

        The networks' products are small: BLAS runs them on one thread (its
        threads, waiting on each other on a loaded machine, made a read in a
        tag-given region six times slower)."""
        with _blas().limit(limits=1, user_api="blas"):
            return self._read(image, region, tower_height, camera)

    def _read(self, image, region, tower_height, camera) -> list[LightDetection]:
        in_region = region is not None and tower_height is not None
        thr = self.region_threshold if in_region else None
        boxes = self.detector.detect(image, region=region, tower_height=tower_height, threshold=thr)
        boxes = boxes[: REGION_CANDIDATES if in_region else self.candidates]
        if not boxes:
            return []
        variants, p_no = self.check(image, [b.xywh for b in boxes], tower_height)
        picks = choose(variants, p_no, self.region_reject if in_region else self.reject, self.max_detections)
        chosen = [(boxes[i], v) for i, v in picks]
        probs = self.classify(image, [v for _, v in chosen])
        return [LightDetection(box=tuple(int(round(c)) for c in v), state=int(p.argmax()), score=b.score,
                               probabilities=tuple(float(x) for x in p), camera=camera)
                for (b, v), p in zip(chosen, probs) if p.max() >= self.min_confidence]


_CONTROLLER: list[ThreadpoolController] = []


def _blas() -> ThreadpoolController:
    """The process's thread-pool controller (made once: it looks the libraries up)."""
    if not _CONTROLLER:
        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0]


REFINE_HEIGHTS = (1.0, 0.82, 0.68)
#: detector hits the networks look at inside a tag-given region (one tower is expected there)
REGION_CANDIDATES = 12
#: where a box of the expected height is put against a hit: its top, middle, bottom
SNAP_ANCHORS = (0.0, 0.5, 1.0)

#: (dx, dy, scale) of the crops a tower is read from: dx of its width, dy of its height
JITTER = ((0.0, 0.0, 1.0), (-0.12, 0.0, 1.0), (0.12, 0.0, 1.0), (0.0, -0.04, 1.0), (0.0, 0.04, 1.0),
          (0.0, 0.0, 0.92), (0.0, 0.0, 1.08))


def jittered(box, j) -> tuple[float, float, float, float]:
    """``box`` shifted by (dx * w, dy * h) and scaled by ``scale`` about its centre."""
    dx, dy, k = j
    x, y, w, h = (float(v) for v in box)
    cx, cy = x + w / 2 + dx * w, y + h / 2 + dy * h
    return (cx - w * k / 2, cy - h * k / 2, w * k, h * k)


def snapped(box, tower_height: float) -> list[tuple[float, float, float, float]]:
    """Boxes ``tower_height`` high (the tower's width for that height),
    centred on ``box`` across and anchored at its top, middle and bottom
    (:data:`SNAP_ANCHORS`)."""
    x, y, w, h = (float(v) for v in box)
    nh = float(tower_height)
    nw = nh * TOWER_W / TOWER_H
    return [(x + w / 2 - nw / 2, y + a * (h - nh), nw, nh) for a in SNAP_ANCHORS]


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


def save_detector(path: str | Path, vector: np.ndarray, **settings) -> None:
    """Write a detector vector, its :class:`TowerDetector` settings and the
    reader's ``reject`` level (the tower check's "no tower" probability at
    which a hit is dropped), ``region_threshold`` and ``region_reject``."""
    np.savez_compressed(path, detector=np.asarray(vector, np.float32), settings=np.array(json.dumps(settings)))
