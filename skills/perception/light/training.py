"""Training the light models: ``rll-bt vision train-light``.

Steps (progress is reported through ``progress(text)``):

1. render chunks of labelled frames from the PyBullet world in worker
   processes (:mod:`.dataset`), for training and, from other layouts, a
   held-out set;
2. train the HOG + linear SVM tower detector, then mine hard negatives
   (false detections on the training frames) and train again, ``rounds``
   times;
3. calibrate the detector's score threshold and minimum support on the
   training frames: the most recall with no false detection there;
4. train the network with scaled conjugate gradient on tower crops, both
   jittered truth boxes and the detector's own boxes;
5. evaluate detector and network on the held-out frames and write the
   model files and a JSON report into the output directory.

The full run is sized for 10 minutes on 2 cores; ``quick`` is a tiny run
for tests (minutes of quality, seconds of time).
"""
from __future__ import annotations

import json
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from rll_bt.clock import WallClock
from rll_bt.errors import UserError

from .dataset import ChunkResult, ChunkSpec, PackedFrame, make_chunk
from .evaluation import LightScore
from .hog import TowerDetector, crop_window, iou, make_hog, select, train_svm, window_features, window_for_tower
from .mlp import DEFAULT_SIZE, N_STATES, NO_TOWER, Mlp, crop_features
from .reader import (CHECKER_FILE, CLASSIFIER_FILE, DETECTOR_FILE, REFINE_HEIGHTS, REPORT_FILE, LightReader,
                     refine_box, save_detector)

PROFILES = ("rcll2016", "rcll2025")
HELDOUT_SEED = 1_000_003


@dataclass
class TrainOptions:
    out: Path
    samples: int = 1000            # rendered training frames
    seed: int = 0
    quick: bool = False
    workers: int = 2
    rounds: int = 2                # hard-negative rounds
    hidden: int = 32
    iterations: int = 300          # SCG iterations (each network)
    heldout: int | None = None     # rendered held-out frames (default samples / 3)

    def __post_init__(self):
        if self.samples < 10:
            raise UserError(f"--samples must be at least 10, not {self.samples}")
        if self.workers < 1:
            raise UserError(f"--workers must be at least 1, not {self.workers}")


def plan(opts: TrainOptions) -> tuple[list[ChunkSpec], list[ChunkSpec]]:
    """Chunks (one seeded world each) for training and for the held-out set."""
    per = 20 if opts.quick else 50
    n_train = max(1, round(opts.samples / per))
    train = []
    for i in range(n_train):
        n = opts.samples // n_train + (1 if i < opts.samples % n_train else 0)
        free = max(1, n // 4)
        train.append(ChunkSpec(PROFILES[i % 2], opts.seed * 7919 + i, n - free, free, int(n * 0.7)))
    held = opts.heldout if opts.heldout is not None else max(10, opts.samples // 3)
    n_held = max(1, round(held / per))
    heldout = []
    for i in range(n_held):
        n = held // n_held + (1 if i < held % n_held else 0)
        free = max(1, int(n * 0.3))
        heldout.append(ChunkSpec(PROFILES[(i + 1) % 2], HELDOUT_SEED + opts.seed * 7919 + i, n - free, free, 0,
                                 strength=(0.3, 1.0), extract=False))
    return train, heldout


def _chunk_job(spec: ChunkSpec) -> ChunkResult:
    from .scenes import sim_world_class
    return make_chunk(spec, sim_world_class())


@dataclass
class FrameHits:
    """What the detector finds in one frame at a low threshold, for mining and calibration."""
    boxes: np.ndarray             # N x 4 tower boxes after non-maximum suppression
    scores: np.ndarray            # N SVM scores
    false: np.ndarray             # N bools: matches no tower
    crops: np.ndarray             # N x variants x 24 x 6 x 3 network crops (REFINE_HEIGHTS, DEFAULT_SIZE)
    hard: np.ndarray              # HOG features of the strongest false hits


def _mine_job(args) -> list[FrameHits]:
    vector, frames, low, per_frame = args
    det = TowerDetector(vector, threshold=low)
    hog = make_hog()
    out = []
    for f in frames:
        img = f.image
        boxes, scores = det.raw_hits(img, max_hits=300)
        kept = select(boxes, scores, low, 1, det.nms_overlap)[:40]
        false = np.array([all(iou(k.xywh, t.box) < 0.2 for t in f.truths) for k in kept], bool)
        hard = [crop_window(img, window_for_tower(k.xywh)) for k, bad in zip(kept, false) if bad][:per_frame]
        crops = np.stack([[crop_window(img, refine_box(k.xywh, v), DEFAULT_SIZE) for v in REFINE_HEIGHTS]
                          for k in kept]) if kept else \
            np.zeros((0, len(REFINE_HEIGHTS), DEFAULT_SIZE[1], DEFAULT_SIZE[0], 3), np.uint8)
        out.append(FrameHits(np.array([k.xywh for k in kept], np.float32).reshape(-1, 4),
                             np.array([k.score for k in kept], np.float32), false, crops,
                             window_features(hog, hard)))
    return out


def _pool(workers: int):
    ctx = multiprocessing.get_context("fork") if "fork" in multiprocessing.get_all_start_methods() else None
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx)


def _split(items: list, n: int) -> list[list]:
    n = max(1, min(n, len(items)))
    return [items[i::n] for i in range(n)]


def calibrate(frames: list[PackedFrame], hits: list[FrameHits], no_tower: list[np.ndarray], low: float
              ) -> tuple[float, float, dict]:
    """The detector threshold and the tower check's "no tower" level at which
    a hit is dropped: no false detection on the tower-free ``frames``, and
    then the most recall, each false detection elsewhere (a tower's mount,
    a misplaced box) costing two hits."""
    top = max((float(h.scores.max()) for h in hits if len(h.scores)), default=low + 1.0)
    best = None
    for reject in (0.5, 0.3, 0.2, 0.1, 0.05):
        for t in sorted(set(np.round(np.linspace(low, max(top, low + 0.1), 40), 4))):
            score = LightScore()
            for f, h, p in zip(frames, hits, no_tower):
                keep = (h.scores >= t) & (p < reject)
                score.add(f.truths, [(tuple(b), 0) for b in h.boxes[keep]])
            # no false detection on tower-free frames; then recall, less two per other false detection
            key = (score.false_free, -(score.hits - 2 * (score.false_all - score.false_free)), -reject, t)
            if best is None or key < best[0]:
                best = (key, t, reject, score)
    _, t, reject, score = best
    return float(t), float(reject), {"threshold": float(t), "reject": float(reject),
                                     "train_recall": score.hits / max(score.required, 1),
                                     "train_false": score.false_all, "train_false_free": score.false_free,
                                     "train_frames": score.frames}


def train_light(opts: TrainOptions, progress: Callable[[str], None] = lambda s: None,
                clock=None) -> dict:
    """Train detector and network; write them and a report into ``opts.out``."""
    clock = clock or WallClock()
    t_start = clock.now()

    def say(text):
        progress(f"[{clock.now() - t_start:6.1f} s] {text}")

    out = Path(opts.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create the output directory: {exc}", where=str(out)) from None
    train_specs, held_specs = plan(opts)
    say(f"rendering {sum(s.towers + s.free for s in train_specs)} training frames "
        f"(+{sum(s.pasted for s in train_specs)} composed) and "
        f"{sum(s.towers + s.free for s in held_specs)} held-out frames with {opts.workers} workers")
    pos, neg, crops, states, frames, heldout = [], [], [], [], [], []
    jobs = [(s, True) for s in train_specs] + [(s, False) for s in held_specs]
    with _pool(opts.workers) as pool:
        for k, ((spec, is_train), res) in enumerate(zip(jobs, pool.map(_chunk_job, [j[0] for j in jobs]))):
            if is_train:
                pos.append(res.pos)
                neg.append(res.neg)
                crops.append(res.crops)
                states.append(res.states)
                frames.extend(res.frames)
            else:
                heldout.extend(res.frames)
            if (k + 1) % max(1, len(jobs) // 10) == 0 or k + 1 == len(jobs):
                say(f"  chunk {k + 1}/{len(jobs)}")
        pos_f, neg_f = np.vstack(pos), np.vstack(neg)
        crops_a, states_a = np.concatenate(crops), np.concatenate(states)
        if len(pos_f) == 0 or len(crops_a) == 0:
            raise UserError("no tower was rendered; cannot train (is the sim world working?)")
        say(f"{len(pos_f)} tower windows, {len(neg_f)} random negatives, {len(crops_a)} tower crops, "
            f"{len(frames)} frames for mining")

        # -- detector: SVM, hard negatives, SVM again ------------------------
        rng = np.random.default_rng(opts.seed)
        mine = [frames[i] for i in rng.permutation(len(frames))[: (40 if opts.quick else 500)]]
        per_frame = max(2, 3000 // max(1, len(mine)))     # hard negatives per frame and round
        low = -0.8
        hard_all = np.zeros((0, pos_f.shape[1]), np.float32)
        vector = train_svm(pos_f, neg_f)
        say(f"SVM round 0 trained on {len(pos_f)} + {len(neg_f)} windows")
        hits: list[FrameHits] = []
        for r in range(opts.rounds + 1):
            hits = []
            for part in pool.map(_mine_job, [(vector, fs, low, per_frame) for fs in _split(mine, opts.workers * 2)]):
                hits.extend(part)
            order = [f for fs in _split(mine, opts.workers * 2) for f in fs]
            mine = order
            hard = np.vstack([h.hard for h in hits]) if hits else hard_all[:0]
            say(f"round {r}: {len(hard)} false windows on {len(mine)} frames")
            if r == opts.rounds:
                break
            hard_all = np.vstack([hard_all, hard])
            vector = train_svm(pos_f, np.vstack([neg_f, hard_all]))
            say(f"SVM round {r + 1} trained with {len(hard_all)} hard negatives")
        # -- network: truth crops, the detector's own boxes, and its false hits --
        # the first half of the mining frames teaches the network, the second calibrates
        half = len(mine) // 2
        det_crops, det_states, neg_crops = [], [], []
        for j, (f, h) in enumerate(zip(mine, hits)):
            for k in range(len(h.scores)):
                if h.false[k]:
                    if j < half:
                        neg_crops.extend(h.crops[k])
                    continue
                for t in f.truths:
                    if t.clean and t.box[3] >= 20 and iou(tuple(h.boxes[k]), t.box) >= 0.3:
                        det_crops.append(h.crops[k][0])
                        det_states.append(t.state)
                        break
    neg_crops = [neg_crops[i] for i in rng.permutation(len(neg_crops))[: 2 * len(crops_a)]]
    towers = crops_a[states_a < N_STATES]
    tower_states = states_a[states_a < N_STATES]
    if det_crops:
        towers = np.concatenate([towers, np.stack(det_crops)])
        tower_states = np.concatenate([tower_states, np.asarray(det_states, np.int64)])
    misplaced = [crops_a[states_a == NO_TOWER]] + ([np.stack(neg_crops)] if neg_crops else [])
    not_towers = np.concatenate(misplaced)

    def features(crops):
        return np.stack([crop_features(c, DEFAULT_SIZE) for c in crops]).astype(np.float64)

    def tick(k, _, fx):
        if k % 100 == 0:
            say(f"  SCG iteration {k}: loss {fx:.4f}")

    true_boxes = crops_a[states_a < N_STATES]          # the check learns well-placed boxes only
    x_check = features(np.concatenate([true_boxes, not_towers]))
    y_check = np.concatenate([np.zeros(len(true_boxes), np.int64), np.ones(len(not_towers), np.int64)])
    checker = Mlp.create(x_check.shape[1], opts.hidden, DEFAULT_SIZE, seed=opts.seed + 1, n_out=2)
    say(f"training the tower check ({x_check.shape[1]} inputs, {opts.hidden} hidden, tower / no tower) on "
        f"{len(true_boxes)} tower and {len(not_towers)} other crops with SCG, {opts.iterations} iterations")
    checker.train(x_check, y_check, max_iter=opts.iterations, decay=1e-3, callback=tick)
    x, y = features(towers), tower_states
    net = Mlp.create(x.shape[1], opts.hidden, DEFAULT_SIZE, seed=opts.seed)
    say(f"training the light network ({x.shape[1]} inputs, {opts.hidden} hidden, 8 states) on {len(x)} "
        f"tower crops with SCG, {opts.iterations} iterations")
    net.train(x, y, max_iter=opts.iterations, decay=1e-3, callback=tick)
    no_tower = []
    for h in hits[half:]:
        if len(h.crops):
            n, v = h.crops.shape[:2]
            p = checker.probabilities(features(h.crops.reshape((n * v,) + h.crops.shape[2:])))[:, 1]
            no_tower.append(p.reshape(n, v).min(axis=1))
        else:
            no_tower.append(np.zeros(0))
    threshold, reject, cal = calibrate(mine[half:], hits[half:], no_tower, low)
    support = 1
    settings = {"threshold": threshold, "min_support": support}
    say(f"detector threshold {threshold:.3f}, tower check rejects at {reject:.2f}: recall "
        f"{cal['train_recall']:.3f}, {cal['train_false']} false on {cal['train_frames']} calibration frames")
    train_acc = float((net.predict(x) == y).mean())

    # -- write and evaluate --------------------------------------------------
    save_detector(out / DETECTOR_FILE, vector, reject=reject, **settings)
    net.save(out / CLASSIFIER_FILE)
    checker.save(out / CHECKER_FILE)
    reader = LightReader.load(out)
    say(f"evaluating on {len(heldout)} held-out frames")
    score = evaluate_parallel(out, heldout, opts.workers)
    report = {
        "options": {k: (str(v) if isinstance(v, Path) else v) for k, v in asdict(opts).items()},
        "detector": {**cal, "min_support": support, "windows_pos": int(len(pos_f)), "windows_neg": int(len(neg_f)),
                     "hard_negatives": int(len(hard_all))},
        "network": {"crops": int(len(x)), "train_accuracy": train_acc, "hidden": opts.hidden},
        "tower_check": {"crops": int(len(x_check)),
                        "train_accuracy": float((checker.predict(x_check) == y_check).mean())},
        "heldout": score.metrics(),
        "seconds": clock.now() - t_start,
        "files": {p: os.path.getsize(out / p) for p in (DETECTOR_FILE, CLASSIFIER_FILE, CHECKER_FILE)},
    }
    del reader
    (out / REPORT_FILE).write_text(json.dumps(report, indent=1))
    return report


def _eval_job(args) -> LightScore:
    model_dir, frames = args
    from .evaluation import evaluate
    reader = LightReader.load(model_dir)
    return evaluate(lambda img: [(d.box, d.state) for d in reader.read(img)], frames)


def evaluate_parallel(model_dir, frames: list[PackedFrame], workers: int) -> LightScore:
    """Score the models in ``model_dir`` on ``frames`` using ``workers`` processes."""
    if not frames:
        return LightScore()
    with _pool(workers) as pool:
        return LightScore.combine(pool.map(_eval_job, [(str(model_dir), fs) for fs in _split(frames, workers)]))
