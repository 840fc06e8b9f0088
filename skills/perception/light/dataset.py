"""Training and test material for the light models, made in worker processes.

A *chunk* is one world (a layout of a profile, seeded) from which a worker
renders frames showing towers and tower-free frames, replaces the hall
behind the stations in some by other backdrops (procedural, photographs,
collages: :func:`.photos.backdrop`), and composes further frames by pasting
rendered and drawn towers onto such backdrops.  Training uses the
``train`` photographs, the benchmark the ``heldout`` ones.  Every
frame gets photometric augmentation, then the worker cuts out

- detector positives (HOG of the window around each fully visible tower,
  slightly jittered, mirrored at random) and random negative windows,
- classifier crops of each fully visible tower (jittered like a detector's
  box) with its state, and badly placed crops of it (stretched over the
  mount, slid up off the lights) as "no tower",

and keeps the frames themselves (JPEG-packed, with their labels) for
hard-negative mining and evaluation.  Labels: tower boxes (x, y, w, h)
pixels; states 0..7 (green 1, yellow 2, red 4).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .augment import photometric
from .hog import crop_window, make_hog, random_negatives, window_features, window_for_tower
from .mlp import DEFAULT_SIZE, NO_TOWER
from .photos import backdrop
from .synth import Sprite, drawn_tower, paste

#: a tower a detector must find: fully visible and at least this tall (pixels)
MIN_REQUIRED_HEIGHT = 28
#: classifier crops and detector positives are cut from towers at least this tall
MIN_TRAIN_HEIGHT = 20


@dataclass
class Truth:
    box: tuple[int, int, int, int]
    state: int
    clean: bool                     # fully visible, inside the frame
    region: tuple[int, int, int, int] | None = None   # where its station's tag says it is
    tower_height: float | None = None                  # its height there, pixels
    roi: tuple[int, int, int, int] | None = None       # its box by the same tag pose, no margin

    @property
    def required(self) -> bool:
        return self.clean and self.box[3] >= MIN_REQUIRED_HEIGHT


@dataclass
class PackedFrame:
    """A frame stored as JPEG bytes with its towers; ``source`` says where
    it came from ("render", "render+bg", "paste", "free-render", "free-paste")."""
    data: bytes
    truths: list[Truth]
    source: str
    distance: float | None = None   # of the tower the view was aimed at, metres

    @property
    def image(self) -> np.ndarray:
        return cv2.imdecode(np.frombuffer(self.data, np.uint8), cv2.IMREAD_COLOR)

    @property
    def tower_free(self) -> bool:
        return not self.truths

    @staticmethod
    def pack(image: np.ndarray, truths, source: str, distance=None) -> PackedFrame:
        ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 95])
        if not ok:
            raise RuntimeError("cannot encode a frame")
        return PackedFrame(buf.tobytes(), list(truths), source, distance)


@dataclass
class ChunkSpec:
    profile: str
    seed: int
    towers: int                     # rendered frames showing a tower
    free: int                       # rendered tower-free frames
    pasted: int                     # frames composed on procedural backgrounds
    strength: tuple[float, float] = (0.3, 1.2)   # photometric augmentation strength
    extract: bool = True            # cut training samples (False: frames only, for tests)
    keep: float = 1.0               # fraction of frames kept packed
    size: tuple[int, int] = (640, 480)
    photos: str = "train"           # which photographs back the frames ("train" or "heldout")
    # where the frames come from: "world" (rendered from the simulated world, composed frames and
    # photometric augmentation added), or "module:function" making finished frames,
    # function(seed, towers, free, photos) -> [(BGR image, [Truth])] (another renderer, for the
    # benchmark's cross-renderer tables; nothing is added to its frames)
    source: str = "world"


@dataclass
class ChunkResult:
    pos: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    neg: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    crops: np.ndarray = field(default_factory=lambda: np.zeros((0, DEFAULT_SIZE[1], DEFAULT_SIZE[0], 3), np.uint8))
    states: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    frames: list[PackedFrame] = field(default_factory=list)
    seconds: float = 0.0


def jitter_box(box, rng: np.random.Generator, shift: tuple[float, float], scale: float):
    """A box moved by up to ``shift`` (fractions of w, h) and scaled by up to ``scale``."""
    x, y, w, h = (float(v) for v in box)
    k = math.exp(rng.uniform(-scale, scale))
    cx = x + w / 2 + rng.uniform(-shift[0], shift[0]) * w
    cy = y + h / 2 + rng.uniform(-shift[1], shift[1]) * h
    return (cx - w * k / 2, cy - h * k / 2, w * k, h * k)


def classifier_crops(image: np.ndarray, box, rng: np.random.Generator, count: int) -> list[np.ndarray]:
    """Crops of a tower box as a detector would cut it (position and scale off a little)."""
    out = [crop_window(image, box, DEFAULT_SIZE)]
    for _ in range(count - 1):
        out.append(crop_window(image, jitter_box(box, rng, (0.2, 0.14), 0.22), DEFAULT_SIZE))
    return out


def misaligned_crops(image: np.ndarray, box, rng: np.random.Generator) -> list[np.ndarray]:
    """Crops of a tower box gone wrong, for the tower check's "no tower"
    class: stretched down over the mount, slid up off the lights, and cut
    short above the bottom light (the check picks among such variants)."""
    x, y, w, h = (float(v) for v in box)
    k = rng.uniform(1.35, 1.8)
    up = rng.uniform(0.35, 0.6)
    short = rng.uniform(0.55, 0.75)
    return [crop_window(image, (x - w * (k - 1) / 2, y, w * k, h * k), DEFAULT_SIZE),
            crop_window(image, (x, y - up * h, w, h), DEFAULT_SIZE),
            crop_window(image, (x + w * (1 - short) / 2, y, w * short, h * short), DEFAULT_SIZE)]


def detector_positives(image: np.ndarray, box, rng: np.random.Generator, count: int) -> list[np.ndarray]:
    out = []
    for k in range(count):
        win = window_for_tower(jitter_box(box, rng, (0.04, 0.02), 0.04) if k else box)
        crop = crop_window(image, win)
        out.append(crop[:, ::-1] if rng.random() < 0.5 else crop)
    return out


def _sky_swap(image: np.ndarray, sky: np.ndarray, rng: np.random.Generator, photos: str) -> np.ndarray:
    bg = backdrop(rng, image.shape[0], image.shape[1], photos)
    out = image.copy()
    out[sky] = bg[sky]
    return out


#: frame sizes composed frames are drawn at (the detector searches any size)
COMPOSED_SIZES = ((640, 480), (512, 384), (480, 360), (400, 300), (320, 240), (800, 600))
#: tower heights pasted or drawn on composed frames, pixels (at most 0.85 of the frame)
COMPOSED_HEIGHTS = (22.0, 260.0)


def _compose(rng: np.random.Generator, size, sprites: list[tuple[np.ndarray, np.ndarray, int]],
             n_towers: int, photos: str = "train", procedural: float = 0.4) -> tuple[np.ndarray, list[Truth]]:
    """A backdrop (``size``, or one of :data:`COMPOSED_SIZES` when None)
    with ``n_towers`` towers: drawn ones (:func:`.synth.drawn_tower`, with
    what they stand on) or, a quarter of them, rendered sprites."""
    if size is None:
        size = COMPOSED_SIZES[int(rng.integers(len(COMPOSED_SIZES)))]
    w, h = size
    img = backdrop(rng, h, w, photos, procedural)
    truths: list[Truth] = []
    hi = min(COMPOSED_HEIGHTS[1], 0.85 * h)
    for _ in range(n_towers):
        state = int(rng.integers(0, 8))
        height = float(np.exp(rng.uniform(math.log(COMPOSED_HEIGHTS[0]), math.log(hi))))
        if sprites and rng.random() < 0.25:
            crop, mask, state = sprites[int(rng.integers(len(sprites)))]
            k = height / crop.shape[0]
            tw, th = max(3, int(round(crop.shape[1] * k))), max(8, int(round(height)))
            sprite = Sprite(cv2.resize(crop, (tw, th), interpolation=cv2.INTER_AREA).astype(np.float32),
                            cv2.resize(mask.astype(np.float32), (tw, th), interpolation=cv2.INTER_AREA),
                            np.zeros((th, tw, 3), np.float32), (0, 0, tw, th))
        else:
            sprite = drawn_tower(rng, height, state)
        tw, th = sprite.box[2], sprite.box[3]
        if tw < 2 or th < 8:
            continue
        for _ in range(20):
            x, y = int(rng.integers(-tw // 3, w - tw + tw // 3)), int(rng.integers(0, max(1, h - th)))
            box = (x, y, tw, th)
            if all(_overlap(box, t.box) == 0 for t in truths):
                break
        else:
            continue
        pasted = paste(img, sprite, x, y)
        truths.append(Truth(pasted, state, pasted == box))
    return img, truths


def _overlap(a, b) -> float:
    ix = max(0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    iy = max(0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    return ix * iy


def free_frames(seed: int, count: int, size=None, photos: str = "train",
                strength: tuple[float, float] = (0.3, 1.2), procedural: float = 0.4) -> list[PackedFrame]:
    """``count`` tower-free frames composed on backdrops (a ``procedural``
    share of them procedural only), augmented (no rendering: cheap material
    for mining and calibrating against false detections)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        img, _ = _compose(rng, size, [], 0, photos, procedural)
        out.append(PackedFrame.pack(photometric(img, rng, float(rng.uniform(*strength))), [], "free-paste"))
    return out


def frame_source(name: str):
    """The frame-making function ``module:function`` (see :class:`ChunkSpec`)."""
    import importlib
    module, _, func = name.partition(":")
    try:
        return getattr(importlib.import_module(module), func)
    except (ImportError, AttributeError, ValueError) as exc:
        raise ValueError(f"no frame source {name!r}: {exc}") from None


def _world_frames(spec: ChunkSpec, rng: np.random.Generator, open_world) -> list:
    """Frames rendered from a world of ``spec`` (some with another backdrop) and composed ones."""
    from .scenes import SceneRenderer, ViewRange
    world = open_world(spec.profile, seed=spec.seed)
    try:
        renderer = SceneRenderer(world, rng, ViewRange(size=spec.size))
        rendered = []
        for i in range(spec.towers + spec.free):
            frame = renderer.sample(tower=i < spec.towers)
            if frame is not None:
                rendered.append(frame)
    finally:
        world.close()
    sprites = []
    for f in rendered:
        for t in f.towers:
            if t.clean and t.box[3] >= 24:
                x, y, w, h = t.box
                sprites.append((f.image[y:y + h, x:x + w].copy(), t.mask, t.state))
    frames: list[tuple[np.ndarray, list[Truth], str, float | None]] = []
    for f in rendered:
        img, source = f.image, ("render" if f.towers else "free-render")
        if f.sky is not None and rng.random() < 0.55:
            img, source = _sky_swap(img, f.sky, rng, spec.photos), source + "+bg"
        truths = [Truth(t.box, t.state, t.clean, t.region, t.tower_height, t.roi) for t in f.towers]
        dist = min((t.distance for t in f.towers), default=None)
        frames.append((img, truths, source, dist))
    for i in range(spec.pasted):
        n = int(rng.integers(0, 4)) if i % 4 else 0
        img, truths = _compose(rng, None, sprites, n, spec.photos)
        frames.append((img, truths, "paste" if truths else "free-paste", None))
    return frames


def make_chunk(spec: ChunkSpec, open_world=None) -> ChunkResult:
    """Render and cut one chunk (runs in a worker process); ``open_world``
    is a world factory (default: :func:`.scenes.world_factory`)."""
    import time

    from .scenes import world_factory
    t0 = time.perf_counter()
    rng = np.random.default_rng(spec.seed)
    res = ChunkResult()
    hog = make_hog()
    pos, neg_imgs, neg_avoid, crops, states = [], [], [], [], []
    if spec.source == "world":
        frames = _world_frames(spec, rng, open_world or world_factory())
    else:
        made = frame_source(spec.source)(spec.seed, spec.towers, spec.free, spec.photos)
        frames = [(img, truths, spec.source.rsplit(":", 1)[-1], None) for img, truths in made]
    for img, truths, source, dist in frames:
        if spec.source == "world":
            img = photometric(img, rng, float(rng.uniform(*spec.strength)))
        if spec.extract:
            for t in truths:
                if t.clean and t.box[3] >= MIN_TRAIN_HEIGHT:
                    pos.extend(detector_positives(img, t.box, rng, 2))
                    for c in classifier_crops(img, t.box, rng, 3):
                        crops.append(c)
                        states.append(t.state)
                    for c in misaligned_crops(img, t.box, rng):
                        crops.append(c)
                        states.append(NO_TOWER)
            neg_imgs.append(img)
            neg_avoid.append([t.box for t in truths])
        if rng.random() < spec.keep:
            res.frames.append(PackedFrame.pack(img, truths, source, dist))
    if spec.extract:
        negs = random_negatives(neg_imgs, 8 * len(neg_imgs), rng, neg_avoid) if neg_imgs else []
        res.pos = window_features(hog, pos)
        res.neg = window_features(hog, negs)
        if crops:
            res.crops = np.stack(crops)
            res.states = np.asarray(states, np.int64)
    res.seconds = time.perf_counter() - t0
    return res
