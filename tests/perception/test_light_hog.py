"""The HOG + SVM tower detector, trained on drawn towers against textured backgrounds."""
import cv2
import numpy as np
import pytest

from skills.perception.light.hog import (WIN, TowerDetector, make_hog, random_negatives, train_svm,
                                         window_features)

COLOURS_ON = [(40, 220, 40), (30, 220, 240), (40, 40, 230)]     # BGR green, yellow, red
COLOURS_OFF = [(30, 60, 30), (30, 60, 70), (30, 30, 70)]


def background(rng, h=240, w=320):
    img = rng.integers(60, 200, (h // 8, w // 8, 3), dtype=np.uint8)
    img = cv2.resize(img, (w, h), interpolation=cv2.INTER_NEAREST)
    for _ in range(6):   # clutter: bars and blobs with strong edges
        x, y = int(rng.integers(0, w - 20)), int(rng.integers(0, h - 20))
        cv2.rectangle(img, (x, y), (x + int(rng.integers(5, 60)), y + int(rng.integers(5, 60))),
                      tuple(int(c) for c in rng.integers(0, 255, 3)), -1)
    return img


def draw_tower(img, x, y, w, state):
    seg = int(round(w * 34 / 36))
    h = 3 * seg + int(w * 45 / 36)
    cv2.rectangle(img, (x, y), (x + w, y + h), (35, 35, 35), -1)           # housing
    for i in range(3):                                                      # red top .. green bottom
        light = 2 - i
        on = (state >> light) & 1
        colour = COLOURS_ON[light] if on else COLOURS_OFF[light]
        top = y + int(w * 45 / 36) + i * seg
        cv2.rectangle(img, (x + 2, top + 1), (x + w - 2, top + seg - 2), colour, -1)
    return (x, y, w, h)


def positives(rng, n):
    crops = []
    for _ in range(n):
        img = background(rng)
        w = int(rng.integers(14, 30))
        box = draw_tower(img, 100, 40, w, int(rng.integers(0, 8)))
        mx, my = int(box[2] * 0.3), int(box[3] * 0.08)
        crops.append(img[box[1] - my:box[1] + box[3] + my, box[0] - mx:box[0] + box[2] + mx])
    return crops


@pytest.fixture(scope="module")
def detector():
    rng = np.random.default_rng(0)
    hog = make_hog()
    pos = window_features(hog, positives(rng, 150))
    bgs = [background(rng) for _ in range(30)]
    neg = window_features(hog, random_negatives(bgs, 600, rng))
    vec = train_svm(pos, neg)
    det = TowerDetector(vec, threshold=0.3)
    # one round of hard negatives, as in the recipe
    hard = []
    for img in bgs:
        for b in det.detect(img):
            hard.append(img[b.y:b.y + b.h, b.x:b.x + b.w])
    if hard:
        vec = train_svm(pos, np.vstack([neg, window_features(hog, hard)]))
    return TowerDetector(vec, threshold=0.3)


def test_finds_the_tower(detector):
    rng = np.random.default_rng(42)
    hits = 0
    for _ in range(10):
        img = background(rng)
        x, y, w = int(rng.integers(20, 250)), int(rng.integers(10, 100)), int(rng.integers(16, 28))
        box = draw_tower(img, x, y, w, int(rng.integers(0, 8)))
        found = detector.detect(img)
        if found:
            b = found[0]
            cx, cy = b.x + b.w / 2, b.y + b.h / 2
            if abs(cx - (box[0] + box[2] / 2)) < box[2] and abs(cy - (box[1] + box[3] / 2)) < box[3] / 2:
                hits += 1
    assert hits >= 8


def test_region_restricts_the_search(detector):
    rng = np.random.default_rng(5)
    img = background(rng)
    draw_tower(img, 200, 40, 22, 7)
    assert detector.detect(img, region=(0, 0, 120, 240)) == []
    assert detector.detect(img, region=(170, 0, 120, 200))


def test_wrong_detector_size_is_a_clear_error():
    with pytest.raises(ValueError, match="window needs"):
        TowerDetector(np.zeros(10, np.float32))
    assert WIN[1] > 2 * WIN[0]      # the window is upright, like the tower
