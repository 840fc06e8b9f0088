"""The reader's choices around the networks: a tag-given tower height puts a
misplaced detector box right, and an unsure reading is not reported."""
import numpy as np
import pytest

from skills.perception.light.hog import TOWER_H, TOWER_W, Box, iou
from skills.perception.light.mlp import Ensemble, Mlp
from skills.perception.light.reader import SNAP_ANCHORS, LightReader, snapped
from tests.support.light_scene import rendered_tower


class FixedDetector:
    """Stands in for the HOG search: always "finds" the given boxes."""

    def __init__(self, boxes):
        self.boxes = boxes
        self.threshold = 0.0

    def detect(self, image, region=None, tower_height=None, threshold=None):
        return [Box(*b, score=1.0) for b in self.boxes]


@pytest.fixture(scope="module")
def shipped():
    return LightReader.load()


@pytest.fixture(scope="module")
def scene():
    """A frame of the project's renderer (what the shipped models are made for) showing a whole
    tower at least 50 px high with a lit red and a lit green lens (state 5), and its box."""
    return rendered_tower(red=True, yellow=False, green=True)


def test_snapped_boxes_have_the_expected_height_and_straddle_the_hit():
    boxes = snapped((100, 50, 10, 30), 44.0)
    assert len(boxes) == len(SNAP_ANCHORS)
    for x, _y, w, h in boxes:
        assert h == pytest.approx(44.0) and w == pytest.approx(44.0 * TOWER_W / TOWER_H)
        assert x + w / 2 == pytest.approx(105.0)
    tops = sorted(b[1] for b in boxes)
    assert tops[-1] == pytest.approx(50.0) and tops[0] == pytest.approx(50 + 30 - 44.0)   # top- and bottom-anchored


def test_a_short_hit_is_put_right_by_the_tags_tower_height(shipped, scene):
    img, truth = scene
    x, y, w, h = truth
    short = (x + 1, y + int(0.3 * h), w - 2, int(0.7 * h))       # the lower 70 %: a misplaced hit
    assert iou(short, truth) < 0.75
    reader = LightReader(FixedDetector([short]), shipped.classifier, shipped.checker, reject=0.9)
    region = (x - 3 * w, y - h, 7 * w, 3 * h)
    with_tag = reader.read(img, region=region, tower_height=float(h))
    assert with_tag, "the tower check rejected every variant"
    assert abs(with_tag[0].box[3] / h - 1.0) <= reader.snap
    assert iou(with_tag[0].box, truth) > iou(short, truth)
    assert with_tag[0].state == 5
    reader.snap = None                                           # no snapping: the hit's own variants only
    without = reader.read(img, region=region, tower_height=float(h))
    assert not without or without[0].box[3] <= short[3]


def test_an_unsure_reading_is_not_reported(shipped, scene):
    img, truth = scene
    flat = Ensemble([Mlp(m.w1, m.b1, np.zeros_like(m.w2), np.zeros_like(m.b2), m.size, m.kind)
                     for m in shipped.classifier.members])   # every state 1/8
    reader = LightReader(FixedDetector([truth]), flat, shipped.checker, reject=0.9)
    assert reader.read(img) == []
    reader.min_confidence = 0.0
    got = reader.read(img)
    assert len(got) == 1 and max(got[0].probabilities) == pytest.approx(1 / 8)
    sure = LightReader(FixedDetector([truth]), shipped.classifier, shipped.checker, reject=0.9)
    assert [d.state for d in sure.read(img)] == [5]


def test_inside_a_tag_given_region_the_check_has_its_own_rejection_level(shipped, scene):
    img, truth = scene
    x, y, w, h = truth
    reader = LightReader(FixedDetector([truth]), shipped.classifier, shipped.checker, reject=1e-9,
                         region_reject=0.9)
    assert reader.read(img) == []                       # the full-frame level drops every hit
    got = reader.read(img, region=(x - 3 * w, y - h, 7 * w, 3 * h), tower_height=float(h))
    assert [d.state for d in got] == [5]
