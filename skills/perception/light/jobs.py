"""The light training's jobs in worker processes: rendered chunks, composed
tower-free frames, the detector's hits on frames (mining, calibration) and
held-out evaluation.

The models depend on the options only, never on ``--workers`` or on which
worker ran what: tower-free frames come in :data:`FREE_CHUNKS` seeded chunks,
callers keep their frames' order, and each worker runs OpenCV on one thread
(its parallel HOG pyramid, under load, at times gave other hits for the same
image; the workers are the parallelism)."""
from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np

from .dataset import ChunkResult, ChunkSpec, PackedFrame, free_frames, make_chunk
from .evaluation import LightScore, evaluate
from .hog import TowerDetector, crop_window, iou, make_hog, select, window_features, window_for_tower
from .mlp import DEFAULT_SIZE
from .reader import REFINE_HEIGHTS, LightReader, refine_box

#: the tallest tower the detector searches, a fraction of the frame's height (composed frames show
#: towers up to 0.9 of it; the detector's own default, 0.6, is what older models were calibrated with)
TOWER_FRACTION = 0.9


def chunk_job(spec: ChunkSpec) -> ChunkResult:
    return make_chunk(spec)


#: composed tower-free frames are made in this many chunks, whatever the number of workers
#: (the chunk seeds, not the workers, decide the frames: any --workers trains the same models)
FREE_CHUNKS = 8


def free_chunks(seed: int, count: int, procedural: float) -> list[tuple[int, int, float]]:
    """:func:`free_job` arguments for ``count`` frames in :data:`FREE_CHUNKS` seeded chunks."""
    return [(seed + k, count // FREE_CHUNKS + (k < count % FREE_CHUNKS), procedural) for k in range(FREE_CHUNKS)]


def free_job(args) -> list[PackedFrame]:
    seed, count, procedural = args
    return free_frames(seed, count, procedural=procedural)


@dataclass
class FrameHits:
    """What the detector finds in one frame at a low threshold, for mining and calibration."""
    boxes: np.ndarray             # N x 4 tower boxes after non-maximum suppression
    scores: np.ndarray            # N SVM scores
    false: np.ndarray             # N bools: matches no tower
    crops: np.ndarray             # N x variants x 32 x 8 x 3 network crops (REFINE_HEIGHTS, DEFAULT_SIZE)
    hard: np.ndarray              # HOG features of the strongest false hits
    state: np.ndarray             # N: state of the clean tower a hit matches, -1 for none
    fit: np.ndarray               # N x variants: IoU of each variant's box with that tower


def mine_job(args) -> list[FrameHits]:
    vector, frames, low, per_frame = args
    det = TowerDetector(vector, threshold=low, max_tower_fraction=TOWER_FRACTION)
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
        state = np.full(len(kept), -1, np.int64)
        fit = np.zeros((len(kept), len(REFINE_HEIGHTS)), np.float32)
        for i, k in enumerate(kept):
            clean = [t for t in f.truths if t.clean and t.box[3] >= 20]
            best = max(clean, key=lambda t: iou(k.xywh, t.box), default=None)
            if best is not None and iou(k.xywh, best.box) >= 0.3:
                state[i] = best.state
                fit[i] = [iou(refine_box(k.xywh, v), best.box) for v in REFINE_HEIGHTS]
        out.append(FrameHits(np.array([k.xywh for k in kept], np.float32).reshape(-1, 4),
                             np.array([k.score for k in kept], np.float32), false, crops,
                             window_features(hog, hard), state, fit))
    return out


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """``workers`` processes, each running OpenCV on one thread (see the module doc)."""
    # spawned, not forked: a forked child inherits OpenCV's thread pool in a state it
    # cannot use, and setting its threads there hung the worker
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=cv2.setNumThreads, initargs=(1,))


def split(items: list, n: int) -> list[list]:
    """``items`` in ``n`` interleaved parts: part k holds items k, k + n, ..."""
    n = max(1, min(n, len(items)))
    return [items[i::n] for i in range(n)]


def eval_job(args) -> LightScore:
    model_dir, frames = args
    reader = LightReader.load(model_dir)
    return evaluate(lambda img: [(d.box, d.state) for d in reader.read(img)], frames)
