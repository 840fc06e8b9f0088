"""The HOG + SVM tower detector, trained on drawn towers against procedural backgrounds."""
import numpy as np
import pytest

from skills.perception.light.backgrounds import procedural_background
from skills.perception.light.hog import (
    WIN,
    TowerDetector,
    crop_window,
    iou,
    make_hog,
    random_negatives,
    select,
    tower_in_window,
    train_svm,
    window_features,
    window_for_tower,
)
from skills.perception.light.synth import drawn_tower, paste

pytestmark = pytest.mark.xdist_group("light-hog")      # one worker trains the module's detector once


def scene(rng, width, state, at=None, h=240, w=320):
    """A drawn tower about ``width`` pixels wide (four times as high) on a procedural background."""
    img = procedural_background(rng, h, w)
    sprite = drawn_tower(rng, 4.0 * width, state)
    tw, th = sprite.box[2], sprite.box[3]
    x, y = at if at is not None else (int(rng.integers(5, w - tw - 5)), int(rng.integers(5, h - th - 5)))
    box = paste(img, sprite, x, y)
    return img, box


@pytest.fixture(scope="module")
def detector():
    rng = np.random.default_rng(0)
    hog = make_hog()
    pos = []
    for _ in range(700):
        img, box = scene(rng, int(rng.integers(9, 26)), int(rng.integers(0, 8)))
        crop = crop_window(img, window_for_tower(box))
        pos += [crop, crop[:, ::-1].copy()]          # mirrored too, as the recipe allows
    bgs = [procedural_background(rng, 240, 320) for _ in range(40)]
    pos_f = window_features(hog, pos)
    neg_f = window_features(hog, random_negatives(bgs, 1500, rng))
    vec = train_svm(pos_f, neg_f)
    det = TowerDetector(vec, threshold=0.0)
    hard = []                                       # one round of hard negatives, as in the recipe
    for img in bgs:
        for b in det.detect(img):
            hard.append(crop_window(img, window_for_tower(b.xywh)))
    if hard:
        vec = train_svm(pos_f, np.vstack([neg_f, window_features(hog, hard)]))
    return TowerDetector(vec, threshold=0.2)


def test_finds_the_tower(detector):
    """Over 48 scenes, the strongest hit is the tower in most, and the tower is
    among the first ten hits (what the reader's tower check looks at) in nearly
    all.  Measured here: 34 and 41 of 48.  The bars leave room for the trained
    vector to differ between CPUs (a run on another machine found the tower
    first in 7 of the first 12 scenes where this machine finds it in 9)."""
    rng = np.random.default_rng(42)
    first = among = 0
    for _ in range(48):
        img, box = scene(rng, int(rng.integers(10, 24)), int(rng.integers(0, 8)))
        found = detector.detect(img)
        first += bool(found) and iou(found[0].xywh, box) >= 0.4
        among += any(iou(b.xywh, box) >= 0.4 for b in detector.detect(img, threshold=0.0)[:10])
    assert first >= 26 and among >= 36, (first, among)


def test_region_restricts_the_search(detector):
    rng = np.random.default_rng(5)
    img, box = scene(rng, 16, 7, at=(230, 60))
    assert detector.detect(img, region=(0, 0, 150, 240)) == []
    found = detector.detect(img, region=(190, 20, 110, 180), tower_height=box[3])
    assert found and iou(found[0].xywh, box) >= 0.4


def test_window_geometry_round_trips():
    box = (100.0, 50.0, 12.0, 49.5)
    win = window_for_tower(box)
    assert win[2] / win[3] == pytest.approx(WIN[0] / WIN[1])
    back = tower_in_window(*win)
    assert back[1] == pytest.approx(box[1]) and back[3] == pytest.approx(box[3])
    assert back[0] + back[2] / 2 == pytest.approx(box[0] + box[2] / 2)


def test_select_keeps_the_best_of_overlapping_hits_and_counts_support():
    boxes = np.array([[10, 10, 8, 33], [11, 10, 8, 33], [12, 11, 8, 33], [100, 10, 8, 33]], np.float32)
    scores = np.array([0.5, 0.9, 0.4, 0.6], np.float32)
    out = select(boxes, scores, threshold=0.0)
    assert [b.x for b in out] == [11, 100] and out[0].support == 3 and out[1].support == 1
    assert [b.x for b in select(boxes, scores, threshold=0.0, min_support=2)] == [11]
    assert select(boxes, scores, threshold=1.0) == []


def test_crop_window_outside_the_image_replicates_the_border():
    img = np.zeros((20, 20, 3), np.uint8)
    img[:, :10] = 200
    crop = crop_window(img, (-10, -5, 20, 60))
    assert crop.shape == (WIN[1], WIN[0], 3)
    assert crop[:, 0].min() == 200


def test_wrong_detector_size_is_a_clear_error():
    with pytest.raises(ValueError, match="window needs"):
        TowerDetector(np.zeros(10, np.float32))
    assert WIN[1] > 2 * WIN[0]      # the window is upright, like the tower
