"""The physical tower reader: candidates of the tag's tower height cover the
tower, its description does not change with exposure, a network trained on
drawn towers finds drawn towers it never saw, the shipped one finds a
rendered tower for the HOG chain's light network to read, and on its own
it reads only where a tag says a tower is."""
from dataclasses import dataclass

import numpy as np
import pytest

from rll_bt.errors import UserError
from skills.perception.light.backgrounds import procedural_background
from skills.perception.light.physical import (
    N_FEATURES,
    NO_TOWER,
    PhysicalReader,
    candidates,
    ious,
    samples,
    tag_like_region,
    train,
)
from skills.perception.light.reader import LightReader
from skills.perception.light.synth import drawn_tower, paste
from tests.support.light_scene import rendered_tower


@dataclass
class Truth:
    box: tuple
    state: int
    required: bool = True
    region: tuple | None = None
    tower_height: float | None = None


@dataclass
class Frame:
    image: np.ndarray
    truths: list


def drawn_frame(rng, state, height=None):
    img = procedural_background(rng, 240, 320)
    sprite = drawn_tower(rng, float(height or rng.uniform(40, 120)), state)
    x = int(rng.integers(40, 320 - sprite.box[2] - 40))
    y = int(rng.integers(10, 240 - sprite.box[3] - 10))
    box = paste(img, sprite, x, y)
    return Frame(img, [Truth(tuple(int(round(v)) for v in box), state)])


def test_candidates_of_the_tags_height_cover_the_tower():
    rng = np.random.default_rng(1)
    for state in (0, 5, 7):
        f = drawn_frame(rng, state, 80)
        t = f.truths[0]
        region, height = tag_like_region(rng, t.box, (320, 240))
        c = candidates(f.image, region, height)
        assert c.features.shape == (len(c.boxes), N_FEATURES) and np.isfinite(c.features).all()
        assert ious(c.boxes, t.box).max() >= 0.55
        rx, ry, rw, rh = region
        assert (c.boxes[:, 0] >= rx - 1).all() and (c.boxes[:, 1] >= ry - 1).all()
        assert (c.boxes[:, 3] == pytest.approx(c.boxes[0, 3])) and c.boxes[0, 3] == pytest.approx(height, rel=0.05)


def test_the_description_does_not_change_with_exposure():
    rng = np.random.default_rng(2)
    f = drawn_frame(rng, 6, 90)
    region, height = tag_like_region(rng, f.truths[0].box, (320, 240))
    dark = (f.image.astype(np.float32) * 0.55).round().astype(np.uint8)
    a, b = candidates(f.image, region, height), candidates(dark, region, height)
    assert np.allclose(a.boxes, b.boxes)
    assert np.abs(a.features - b.features).mean() < 0.02


@pytest.fixture(scope="module")
def trained():
    rng = np.random.default_rng(3)
    frames = [drawn_frame(rng, int(rng.integers(0, 8))) for _ in range(160)]
    x, y = samples(frames, rng)
    assert (y == NO_TOWER).sum() > len(y) / 3 and set(np.unique(y[y < NO_TOWER])) == set(range(8))
    return train(x, y, hidden=16, iterations=200)


@pytest.mark.slow
def test_a_reader_trained_on_drawn_towers_finds_drawn_towers_it_never_saw(trained):
    rng = np.random.default_rng(4)
    found = 0
    for i in range(24):
        f = drawn_frame(rng, i % 8)
        t = f.truths[0]
        region, height = tag_like_region(rng, t.box, (320, 240))
        trained.min_confidence = 0.0
        got = trained.read(f.image, region, height)
        found += bool(got) and ious(np.array([got[0].box], float), t.box)[0] >= 0.3
    assert found >= 20


def test_the_shipped_reader_finds_a_rendered_tower_for_the_light_network_to_read():
    img, box = rendered_tower(red=True, yellow=False, green=True)
    reader = PhysicalReader.load()
    reader.light = LightReader.load()
    x, y, w, h = box
    rng = np.random.default_rng(6)
    for _ in range(3):                                   # the tag's region, a little off each time
        region, height = tag_like_region(rng, box, (img.shape[1], img.shape[0]))
        got = reader.read(img, region, height)
        assert len(got) == 1 and got[0].state == 5
        assert ious(np.array([got[0].box], float), box)[0] >= 0.3
    assert reader.read(img) == reader.light.read(img)   # no region: the chain's full-frame read


@pytest.mark.slow
def test_it_reads_only_in_a_tag_given_region_and_round_trips(trained, tmp_path):
    img = procedural_background(np.random.default_rng(5), 240, 320)
    with pytest.raises(ValueError, match="region"):
        trained.read(img)
    path = tmp_path / "physical.npz"
    trained.save(path)
    back = PhysicalReader.load(path)
    c = candidates(img, (100, 40, 80, 160), 70.0)
    assert np.allclose(back.probabilities(c.features), trained.probabilities(c.features), atol=1e-5)
    with pytest.raises(UserError, match="missing"):
        PhysicalReader.load(tmp_path / "none.npz")
