"""Labelled frames from the world factory: the entry point, labels that match
the world, varied looks, and photographs kept apart for held-out tests."""
import numpy as np
import pytest

from rll_bt.errors import UserError
from skills.perception.light import photos
from skills.perception.light.scenes import SceneRenderer, world_factory


@pytest.fixture(scope="module")
def world():
    w = world_factory()("rcll2016", seed=2)
    yield w
    w.close()


def test_unknown_world_factory_is_a_user_error():
    with pytest.raises(UserError, match="rll_bt.worlds"):
        world_factory("no-such-world")


def test_rendered_frames_label_the_towers_they_show(world):
    r = SceneRenderer(world, np.random.default_rng(1))
    shown = 0
    for _ in range(4):
        f = r.sample(tower=True)
        assert f is not None and f.image.shape == (480, 640, 3)
        assert f.towers
        for t in f.towers:
            x, y, w, h = t.box
            assert 0 <= t.state < 8 and w > 0 and h > 0
            # a tower is upright and taller than wide (36 x 147 mm), unless cut by the frame
            if t.clean and h >= 20:
                assert 2.0 < h / w < 6.5
                shown += 1
        # the backdrop is the hall, not empty space
        assert f.sky is not None and f.sky.any()
    assert shown >= 2


def test_every_sample_gets_another_look(world):
    r = SceneRenderer(world, np.random.default_rng(2))
    looks = set()
    for _ in range(3):
        r.randomise_look()
        lt = world.lighting
        looks.add((round(lt.kelvin), round(lt.exposure, 3), round(lt.azimuth, 3)))
    assert len(looks) == 3


def test_tower_free_views_show_no_tower(world):
    r = SceneRenderer(world, np.random.default_rng(3))
    for _ in range(3):
        f = r.sample(tower=False)
        assert f is not None and f.tower_free


@pytest.mark.skipif(not photos.available("train"), reason="scikit-image (its sample photographs) not installed")
def test_photographs_for_training_and_for_testing_are_apart():
    train = photos.photos("train")
    held = photos.photos("heldout")
    assert train and held
    assert not {p.tobytes()[:4096] for p in train} & {p.tobytes()[:4096] for p in held}
    rng = np.random.default_rng(0)
    crop = photos.photo_backdrop(rng, 120, 160, "heldout")
    assert crop.shape == (120, 160, 3) and crop.dtype == np.uint8
    assert photos.backdrop(rng, 60, 80).shape == (60, 80, 3)
