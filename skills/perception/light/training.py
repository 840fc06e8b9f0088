"""Training the light models: ``rll-bt vision train-light``.

Steps (progress is reported through ``progress(text)``):

1. render chunks of labelled frames from the simulated world in worker
   processes (:mod:`.dataset`), for training and, from other layouts, a
   held-out set;
2. train the HOG + linear SVM tower detector, then mine hard negatives
   (false detections on the training frames: rendered halls, photographs,
   procedural backdrops) and train again, ``rounds`` times;
3. train the tower check (tower / no tower) on truth crops, badly placed
   crops and the detector's own hits, true and false (also on further
   composed tower-free frames, half of those the ones a probe network finds
   most tower-like: :func:`hard_clutter`), and the light network on truth
   crops and the detector's true hits, both with scaled conjugate gradient,
   each an ensemble of ``members`` networks from different starts;
4. calibrate the detector's score threshold and the check's rejection level
   on frames the detector never mined (with extra composed tower-free
   frames): at most one false detection in 2000 tower-free frames, then
   the most recall less what false detections cost (:func:`calibrate`),
   and a threshold and level of their own inside tag-given regions
   (:func:`calibrate_region`);
5. evaluate the chain on the held-out frames and write the model files and
   a JSON report into the output directory.

The full run is sized for 10 minutes on 2 cores; ``quick`` is a tiny run
for tests (minutes of quality, seconds of time).
"""
from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from rll_bt.clock import WallClock
from rll_bt.errors import UserError

from .dataset import ChunkSpec, PackedFrame
from .evaluation import LightScore
from .hog import TowerDetector, iou, train_svm
from .jobs import TOWER_FRACTION, FrameHits, chunk_job, eval_job, free_chunks, free_job, mine_job, split, worker_pool
from .mlp import DEFAULT_SIZE, N_STATES, NO_TOWER, Ensemble, Mlp, crop_features
from .photos import photos
from .reader import (
    CHECKER_FILE,
    CLASSIFIER_FILE,
    DETECTOR_FILE,
    REFINE_HEIGHTS,
    REGION_CANDIDATES,
    REPORT_FILE,
    LightReader,
    choose,
    refine_box,
    save_detector,
)

PROFILES = ("rcll2016", "rcll2025")
HELDOUT_SEED = 1_000_003
#: the tower check's "no tower" levels calibration tries
REJECT_LEVELS = (0.5, 0.3, 0.2, 0.15, 0.1, 0.05, 0.02)
#: hits a false detection on a tower-free calibration frame costs (:func:`calibrate`)
FREE_FALSE_COST = 10
#: false detections per tower-free calibration frame calibration allows: half the aim of 1 in 1000
FREE_FALSE_RATE = 0.0005


@dataclass
class TrainOptions:
    out: Path
    samples: int = 1000            # rendered training frames
    seed: int = 0
    quick: bool = False
    workers: int = 2
    rounds: int = 2                # hard-negative rounds
    hidden: int = 48               # the light network's hidden units
    check_hidden: int = 48         # the tower check's
    iterations: int = 300          # SCG iterations (each network)
    members: int = 3               # networks per ensemble (the check's and the light network's)
    heldout: int | None = None     # rendered held-out frames (default samples / 3)
    source: str = "world"          # where frames come from (:class:`.dataset.ChunkSpec`)

    def __post_init__(self):
        if self.samples < 10:
            raise UserError(f"--samples must be at least 10, not {self.samples}")
        if self.workers < 1:
            raise UserError(f"--workers must be at least 1, not {self.workers}")
        if self.members < 1:
            raise UserError(f"--members must be at least 1, not {self.members}")


def plan(opts: TrainOptions) -> tuple[list[ChunkSpec], list[ChunkSpec]]:
    """Chunks (one seeded world each) for training and for the held-out set."""
    per = 20 if opts.quick else 50
    n_train = max(1, round(opts.samples / per))
    train = []
    for i in range(n_train):
        n = opts.samples // n_train + (1 if i < opts.samples % n_train else 0)
        free = max(1, n // 4)
        pasted = int(n * 3.0) if opts.source == "world" else 0
        train.append(ChunkSpec(PROFILES[i % 2], opts.seed * 7919 + i, n - free, free, pasted, source=opts.source))
    held = opts.heldout if opts.heldout is not None else max(10, opts.samples // 3)
    n_held = max(1, round(held / per))
    heldout = []
    for i in range(n_held):
        n = held // n_held + (1 if i < held % n_held else 0)
        free = max(1, int(n * 0.3))
        heldout.append(ChunkSpec(PROFILES[(i + 1) % 2], HELDOUT_SEED + opts.seed * 7919 + i, n - free, free, 0,
                                 strength=(0.3, 1.0), extract=False, source=opts.source,
                                 photos="train" if opts.source == "world" else "heldout"))
    return train, heldout


def train_ensemble(x: np.ndarray, y: np.ndarray, hidden: int, n_out: int, seed: int, members: int,
                   iterations: int, callback=None) -> Ensemble:
    """``members`` networks on the same crops from different starts."""
    nets = []
    for i in range(members):
        m = Mlp.create(x.shape[1], hidden, DEFAULT_SIZE, seed=seed + 17 * i, n_out=n_out)
        m.train(x, y, max_iter=iterations, decay=1e-3, callback=callback)
        nets.append(m)
    return Ensemble(nets)


def hard_clutter(x: np.ndarray, y: np.ndarray, x_clutter: np.ndarray, n: int, opts: TrainOptions,
                 rng: np.random.Generator) -> np.ndarray:
    """Which ``n`` of the clutter crops (the detector's false hits on
    tower-free frames) the check learns from besides its crops ``x``
    (labels ``y``: 0 tower, 1 not): half at random, half the ones a probe
    network (one, half the iterations, trained with the random half) finds
    most tower-like: hard-negative mining for the check."""
    pick = rng.permutation(len(x_clutter))[:n // 2]
    probe = train_ensemble(np.concatenate([x, x_clutter[pick]]), np.concatenate([y, np.ones(len(pick), y.dtype)]),
                           opts.check_hidden, 2, opts.seed + 3, 1, max(1, opts.iterations // 2))
    order = np.argsort(probe.probabilities(x_clutter)[:, 1], kind="stable")    # most tower-like first
    taken = np.zeros(len(x_clutter), bool)
    taken[pick] = True
    return np.concatenate([pick, order[~taken[order]][:n - len(pick)]])


def calibrate(frames: list[PackedFrame], hits: list[FrameHits], no_tower: list[np.ndarray], low: float,
              limit: int = 3, free_rate: float | None = None) -> tuple[float, float, dict]:
    """The detector threshold and the tower check's "no tower" level at which
    a hit is dropped, with the reader's own choice of hits
    (:func:`.reader.choose`): at most ``free_rate`` false detections per
    tower-free frame (rendered or composed; :data:`FREE_FALSE_RATE`, half
    the aim, for the margin unseen backdrops need), then the most recall,
    each false detection costing hits: two on frames with towers (on a
    tower's mount, a misplaced box), ten on tower-free ones (a tower that is
    not there sends a robot to act on it; a tower missed in one frame is
    found in the next).  ``no_tower`` holds each frame's hits x variants
    probabilities."""
    free_rate = FREE_FALSE_RATE if free_rate is None else free_rate
    top = max((float(h.scores.max()) for h in hits if len(h.scores)), default=low + 1.0)
    # only hits some setting can keep matter: those the loosest check keeps
    cases = []
    for f, h, p in zip(frames, hits, no_tower):
        keep = np.flatnonzero(p.min(axis=1) < 0.5) if len(p) else np.zeros(0, int)
        vs = [[refine_box(h.boxes[k], v) for v in REFINE_HEIGHTS] for k in keep]
        cases.append((f, h.scores[keep], p[keep], vs))
    allowed = int(free_rate * sum(1 for f in frames if not f.truths))
    best = None
    for reject in REJECT_LEVELS:
        for t in sorted(set(np.round(np.linspace(low, max(top, low + 0.1), 30), 4))):
            score = LightScore()
            for f, scores, p, vs in cases:
                n = int((scores >= t).sum())          # hits come strongest first
                picks = choose(vs[:n], p[:n], reject, limit)
                score.add(f.truths, [(tuple(b), 0) for _, b in picks])
            other = score.false_all - score.false_free
            key = (max(0, score.false_free - allowed),
                   -(score.hits - 2 * other - FREE_FALSE_COST * score.false_free), -reject, t)
            if best is None or key < best[0]:
                best = (key, t, reject, score)
    _, t, reject, score = best
    return float(t), float(reject), {"threshold": float(t), "reject": float(reject),
                                     "train_recall": score.hits / max(score.required, 1),
                                     "train_false": score.false_all, "train_false_free": score.false_free,
                                     "train_false_allowed": allowed,
                                     "train_frames": score.frames, "train_free_frames": score.free_frames}


def calibrate_region(vector: np.ndarray, checker: Mlp | Ensemble, frames: list[PackedFrame], low: float,
                     threshold: float, reject: float) -> tuple[float, float, dict]:
    """The detector threshold and the check's rejection level inside a
    tag-given region (where a tower is expected): those with the most recall
    at which reading each required tower's region gives no more false first
    detections than the full-frame ``threshold`` and ``reject``.  The hits'
    variants are the reader's for a tag-given region (:meth:`LightReader.check`)."""
    det = TowerDetector(vector, threshold=low, max_tower_fraction=TOWER_FRACTION)
    reader = LightReader(det, None, checker)
    reads = []                         # per tower: (truth, scores, p_no, variants)
    for f in frames:
        img = None
        for t in f.truths:
            if not t.required or t.region is None:
                continue
            img = f.image if img is None else img
            kept = det.detect(img, region=t.region, tower_height=t.tower_height)[:REGION_CANDIDATES]
            vs, p = reader.check(img, [k.xywh for k in kept], t.tower_height)
            reads.append((t, np.array([k.score for k in kept]), p, vs))

    def count(t_region, r_region):
        hits = false = 0
        for truth, scores, p, vs in reads:
            n = int((scores >= t_region).sum())
            picks = choose(vs[:n], p[:n], r_region, 1)
            if picks:
                if iou(picks[0][1], truth.box) >= 0.3:
                    hits += 1
                else:
                    false += 1
        return hits, false

    _, allowed = count(threshold, reject)
    best = (threshold, reject, *count(threshold, reject))
    for r in REJECT_LEVELS:
        for t in np.round(np.linspace(max(low, threshold - 0.4), threshold, 25), 4):
            hits, false = count(float(t), r)
            if false <= allowed and hits > best[2]:
                best = (float(t), r, hits, false)
    t, r, hits, false = best
    return t, r, {"region_threshold": t, "region_reject": r, "region_recall": hits / max(len(reads), 1),
                  "region_false": false, "region_towers": len(reads)}


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
    n_photos = len(photos("train"))
    say(f"backdrops: procedural and {n_photos} photographs" if n_photos else
        "backdrops: procedural only (install scikit-image for its sample photographs: "
        "pip install 'rll-bt[vision-train]')")
    say(f"rendering {sum(s.towers + s.free for s in train_specs)} training frames "
        f"(+{sum(s.pasted for s in train_specs)} composed) and "
        f"{sum(s.towers + s.free for s in held_specs)} held-out frames with {opts.workers} workers")
    pos, neg, crops, states, frames, heldout = [], [], [], [], [], []
    jobs = [(s, True) for s in train_specs] + [(s, False) for s in held_specs]
    with worker_pool(opts.workers) as pool:
        for k, ((_spec, is_train), res) in enumerate(zip(jobs, pool.map(chunk_job, [j[0] for j in jobs]))):
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
        order = rng.permutation(len(frames))
        n_mine, n_towers, n_free = (40, 20, 10) if opts.quick else (500, 400, 2000)
        n_extra, n_clutter = (10, 200) if opts.quick else (1000, 12000)
        mine = [frames[i] for i in order[:n_mine]]
        # calibration: frames the detector never mined, every tower-free one of them
        # and extra composed tower-free frames (false detections are what it must rule out)
        rest = [frames[i] for i in order[n_mine:]]
        calib = [f for f in rest if f.truths][:n_towers] + [f for f in rest if not f.truths]
        # calibration's composed tower-free frames are photographs and collages: procedural
        # backdrops (drawn to look like towers at times) teach the models, the calibration
        # sets the false-detection rate a camera's real scenes give
        for part in pool.map(free_job, free_chunks(opts.seed * 7919 + 555_000, n_free, 0.0)):
            calib.extend(part)
        calib = calib or mine
        per_frame = max(2, 3000 // max(1, len(mine)))     # hard negatives per frame and round
        low = -0.8
        hard_all = np.zeros((0, pos_f.shape[1]), np.float32)
        vector = train_svm(pos_f, neg_f)
        say(f"SVM round 0 trained on {len(pos_f)} + {len(neg_f)} windows")

        def detect_all(fs):
            """Frames ``fs`` and their hits, in their order however they fall on the workers
            (the order of the hard negatives steers the SVM)."""
            parts = split(fs, opts.workers * 2)
            hits = [None] * len(fs)
            for k, got in enumerate(pool.map(mine_job, [(vector, p, low, per_frame) for p in parts])):
                hits[k::len(parts)] = got          # part k holds frames k, k + n, ... (_split)
            return fs, hits

        hits: list[FrameHits] = []
        for r in range(opts.rounds + 1):
            mine, hits = detect_all(mine)
            hard = np.vstack([h.hard for h in hits]) if hits else hard_all[:0]
            say(f"round {r}: {len(hard)} false windows on {len(mine)} frames")
            if r == opts.rounds:
                break
            hard_all = np.vstack([hard_all, hard])
            vector = train_svm(pos_f, np.vstack([neg_f, hard_all]))
            say(f"SVM round {r + 1} trained with {len(hard_all)} hard negatives")
        calib, cal_hits = detect_all(calib)
        say(f"{sum(len(h.scores) for h in cal_hits)} hits on {len(calib)} calibration frames")
        # more clutter for the check: the detector's hits on further composed tower-free
        # frames (cheap: no rendering), apart from the calibration frames
        extra = [f for part in pool.map(free_job, free_chunks(opts.seed * 7919 + 777_000, n_extra, 0.4))
                 for f in part]
        _, extra_hits = detect_all(extra)
        clutter = [c for h in extra_hits for k in np.flatnonzero(h.false) for c in h.crops[k]]
        say(f"{len(clutter)} false hit crops on {len(extra)} more tower-free frames")

    # -- the check and the light network learn from truth crops and the detector's own hits --
    # the check learns each true hit's best variant as a tower (it is to pick the best-placed box),
    # the light network every variant that fits well (it must read whichever box the check picks)
    good, good_states, fits, fit_states, bad = [], [], [], [], []
    for h in hits:
        for k in range(len(h.scores)):
            if h.state[k] < 0:
                if h.false[k]:
                    bad.extend(h.crops[k])
                continue
            best = int(np.argmax(h.fit[k]))
            if h.fit[k, best] >= 0.5:
                good.append(h.crops[k][best])
                good_states.append(int(h.state[k]))
            for c, v in zip(h.crops[k], h.fit[k]):
                if v >= 0.6:
                    fits.append(c)
                    fit_states.append(int(h.state[k]))
                elif v < 0.35:
                    bad.append(c)
    true_boxes = crops_a[states_a < N_STATES]
    towers = np.concatenate([true_boxes] + ([np.stack(good)] if good else []))
    tower_states = np.concatenate([states_a[states_a < N_STATES], np.asarray(good_states, np.int64)])
    not_towers = [crops_a[states_a == NO_TOWER]]
    if bad:
        not_towers.append(np.stack([bad[i] for i in rng.permutation(len(bad))[: 3 * len(towers)]]))
    not_towers = np.concatenate(not_towers)

    def tick(k, _, fx):
        if k % 100 == 0:
            say(f"  SCG iteration {k}: loss {fx:.4f}")

    def features(crops):
        return np.stack([crop_features(c, DEFAULT_SIZE) for c in crops])

    x_check = np.concatenate([features(towers), features(not_towers)])
    y_check = np.concatenate([np.zeros(len(towers), np.int64), np.ones(len(not_towers), np.int64)])
    if clutter:
        x_clutter = features(clutter)
        pick = hard_clutter(x_check, y_check, x_clutter, n_clutter, opts, rng)
        say(f"{len(pick)} clutter crops for the check, half of them the most tower-like to a probe network")
        x_check = np.concatenate([x_check, x_clutter[pick]])
        y_check = np.concatenate([y_check, np.ones(len(pick), np.int64)])
        del x_clutter
    say(f"training the tower check ({x_check.shape[1]} inputs, {opts.members} x {opts.check_hidden} hidden, "
        f"tower / no tower) on {len(towers)} tower and {len(x_check) - len(towers)} other crops with SCG, "
        f"{opts.iterations} iterations")
    checker = train_ensemble(x_check, y_check, opts.check_hidden, 2, opts.seed + 1, opts.members, opts.iterations,
                             tick)
    x = np.concatenate([x_check[:len(true_boxes)], features(fits)]) if fits else x_check[:len(true_boxes)]
    y = np.concatenate([tower_states[:len(true_boxes)], np.asarray(fit_states, np.int64)])
    say(f"training the light network ({x.shape[1]} inputs, {opts.members} x {opts.hidden} hidden, 8 states) "
        f"on {len(x)} tower crops with SCG, {opts.iterations} iterations")
    net = train_ensemble(x, y, opts.hidden, N_STATES, opts.seed, opts.members, opts.iterations, tick)
    no_tower = []
    for h in cal_hits:
        if len(h.crops):
            n, v = h.crops.shape[:2]
            p = checker.probabilities(checker.features(h.crops.reshape((n * v,) + h.crops.shape[2:])))[:, 1]
            no_tower.append(p.reshape(n, v))
        else:
            no_tower.append(np.zeros((0, len(REFINE_HEIGHTS))))
    threshold, reject, cal = calibrate(calib, cal_hits, no_tower, low)
    region_threshold, region_reject, region_cal = calibrate_region(vector, checker, calib, low, threshold, reject)
    cal.update(region_cal)
    support = 1
    settings = {"threshold": threshold, "min_support": support, "region_threshold": region_threshold,
                "region_reject": region_reject, "max_tower_fraction": TOWER_FRACTION}
    say(f"detector threshold {threshold:.3f}, tower check rejects at {reject:.2f}: recall "
        f"{cal['train_recall']:.3f}, {cal['train_false']} false on {cal['train_frames']} calibration frames; "
        f"in tag regions threshold {region_threshold:.3f}, rejects at {region_reject:.2f}: "
        f"recall {region_cal['region_recall']:.3f}, "
        f"{region_cal['region_false']} false on {region_cal['region_towers']} towers")
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
        "network": {"crops": int(len(x)), "train_accuracy": train_acc, "hidden": opts.hidden,
                    "members": opts.members},
        "tower_check": {"crops": int(len(x_check)),
                        "train_accuracy": float((checker.predict(x_check) == y_check).mean())},
        "heldout": score.metrics(),
        "seconds": clock.now() - t_start,
        "files": {p: os.path.getsize(out / p) for p in (DETECTOR_FILE, CLASSIFIER_FILE, CHECKER_FILE)},
    }
    del reader
    (out / REPORT_FILE).write_text(json.dumps(report, indent=1))
    return report


def evaluate_parallel(model_dir, frames: list[PackedFrame], workers: int) -> LightScore:
    """Score the models in ``model_dir`` on ``frames`` using ``workers`` processes."""
    if not frames:
        return LightScore()
    with worker_pool(workers) as pool:
        return LightScore.combine(pool.map(eval_job, [(str(model_dir), fs) for fs in split(frames, workers)]))
