"""How well a light reader does on labelled frames.

A tower counts as *required* when it is fully visible and at least
``MIN_REQUIRED_HEIGHT`` pixels tall; a detection matching it (IoU >= 0.3)
is a hit, its state is checked.  Detections matching a tower that is not
required (cut by the frame edge, occluded, tiny) are neither right nor
wrong; every other detection is a false detection.  Metrics:

- ``recall``: required towers hit / required towers
- ``state_accuracy``: hits with the right state / hits (the network's share)
- ``end_to_end``: required towers hit with the right state / required towers
- ``confusion``: 8 x 8 counts, rows the true state, columns the read one
- ``false_per_1000``: false detections per 1000 tower-free frames
- ``false_per_1000_all``: false detections per 1000 frames of any kind
- ``ms_median``/``ms_p95``: time per frame
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np

from rll_bt.clock import Clock, WallClock

from .hog import iou

MATCH_IOU = 0.3


@dataclass
class LightScore:
    required: int = 0
    hits: int = 0
    correct: int = 0
    confusion: np.ndarray = field(default_factory=lambda: np.zeros((8, 8), np.int64))
    frames: int = 0
    free_frames: int = 0
    false_free: int = 0
    false_all: int = 0
    ms: list[float] = field(default_factory=list)

    def add(self, truths, detections: list[tuple[tuple, int]], ms: float | None = None) -> None:
        """One frame: ``truths`` (objects with box, state, required) and
        ``detections`` as (box, state), best first."""
        self.frames += 1
        if not truths:
            self.free_frames += 1
        if ms is not None:
            self.ms.append(ms)
        used = set()
        for t in truths:
            best, best_iou = None, MATCH_IOU
            for i, (box, _) in enumerate(detections):
                v = iou(box, t.box)
                if i not in used and v >= best_iou:
                    best, best_iou = i, v
            if best is not None:
                used.add(best)
            if not t.required:
                continue
            self.required += 1
            if best is not None:
                self.hits += 1
                state = detections[best][1]
                self.confusion[t.state, state] += 1
                self.correct += int(state == t.state)
        false = len(detections) - len(used)
        self.false_all += false
        if not truths:
            self.false_free += false

    @classmethod
    def combine(cls, scores) -> LightScore:
        """One score over the frames of several (e.g. from worker processes)."""
        total = cls()
        for s in scores:
            total.required += s.required
            total.hits += s.hits
            total.correct += s.correct
            total.confusion += s.confusion
            total.frames += s.frames
            total.free_frames += s.free_frames
            total.false_free += s.false_free
            total.false_all += s.false_all
            total.ms.extend(s.ms)
        return total

    def metrics(self) -> dict:
        r = max(self.required, 1)
        return {
            "required_towers": self.required,
            "recall": self.hits / r,
            "state_accuracy": self.correct / max(self.hits, 1),
            "end_to_end": self.correct / r,
            "confusion": self.confusion.tolist(),
            "frames": self.frames,
            "tower_free_frames": self.free_frames,
            "false_detections_free": self.false_free,
            "false_per_1000": 1000.0 * self.false_free / max(self.free_frames, 1),
            "false_per_1000_all": 1000.0 * self.false_all / max(self.frames, 1),
            "ms_median": float(np.median(self.ms)) if self.ms else None,
            "ms_p95": float(np.percentile(self.ms, 95)) if self.ms else None,
        }


def evaluate(read: Callable[[np.ndarray], list[tuple[tuple, int]]], frames: Iterable,
             clock: Clock | None = None) -> LightScore:
    """Run ``read(image) -> [(box, state), ...]`` over frames (with ``image``
    and ``truths``) and score it."""
    clock = clock or WallClock()
    score = LightScore()
    for f in frames:
        img = f.image
        t0 = clock.now()
        dets = read(img)
        score.add(f.truths, dets, (clock.now() - t0) * 1000.0)
    return score


def confusion_table(confusion) -> str:
    """The confusion matrix as text (rows: true state, columns: read state)."""
    c = np.asarray(confusion)
    lines = ["true\\read " + " ".join(f"{j:>5d}" for j in range(8))]
    for i in range(8):
        lines.append(f"{i:>9d} " + " ".join(f"{int(v):>5d}" for v in c[i]))
    return "\n".join(lines)
