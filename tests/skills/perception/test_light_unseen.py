"""The evaluation renderers (renderer B ray-cast, renderer C drawn flat):
towers of the asked size and state with their truth boxes, on photographs
training never sees; and training never learns from them."""
import ast
from pathlib import Path

import numpy as np
import pytest

from skills.perception.light import unseen
from skills.perception.light.dataset import ChunkSpec, make_chunk
from skills.perception.light.training import TrainOptions
from skills.perception.light.unseen import compose, raycast, sketch

LIGHT = Path(unseen.__file__).parents[1]


def test_training_never_imports_the_evaluation_renderers():
    for path in LIGHT.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.ImportFrom):
                names = [node.module or ""] + [a.name for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            assert not any("unseen" in n for n in names), f"{path.name} imports {names}"
    assert TrainOptions("unused").source == "world"


def test_a_raycast_tower_is_as_high_as_asked():
    rng = np.random.default_rng(3)
    for state in (0, 5, 7):
        tower = raycast.random_tower(rng, state)
        light = raycast.random_light(rng, np.full((32, 32, 3), 0.2, np.float32))
        for height in (40.0, 120.0, 200.0):
            patch = raycast.render_tower(rng, tower, light, height)
            assert abs(patch.box[3] - height) <= 0.03 * height + 1
            assert patch.alpha.max() > 0.99 and patch.colour.shape[:2] == patch.alpha.shape
            x, y, w, h = patch.box
            assert 2.0 < h / w < 8.0                     # upright, about a tower's shape


def test_a_lit_lens_glows_and_an_unlit_one_does_not():
    rng = np.random.default_rng(5)
    light = raycast.random_light(rng, np.full((32, 32, 3), 0.2, np.float32))
    dark = raycast.render_tower(rng, raycast.random_tower(rng, 0), light, 100.0)
    lit = raycast.render_tower(rng, raycast.random_tower(rng, 7), light, 100.0)
    assert dark.emission.max() == 0.0 and lit.emission.max() > 0.5


@pytest.mark.parametrize("renderer", compose.RENDERERS)
def test_frames_carry_their_towers_boxes_and_a_tag_like_region(renderer):
    rng = np.random.default_rng(7)
    for _ in range(3):
        img, truths = compose.frame(rng, renderer, 2)
        h, w = img.shape[:2]
        assert img.dtype == np.uint8 and (w, h) in compose.SIZES
        assert truths
        for t in truths:
            x, y, bw, bh = t.box
            assert x >= 0 and y >= 0 and x + bw <= w and y + bh <= h
            assert 30 <= bh <= 220 and t.required and 0 <= t.state <= 7
            rx, ry, rw, rh = t.region
            assert rx <= x and ry <= y and rx + rw >= x + bw and ry + rh >= y + bh
            assert abs(t.tower_height / bh - 1) < 0.15


def test_a_sketched_tower_is_drawn_inside_its_box():
    rng = np.random.default_rng(9)
    spr = sketch.draw(rng, 5, 90.0)
    x, y, w, h = spr.box
    assert 70 <= h <= 110
    inside = spr.alpha[int(y):int(y + h), int(x):int(x + w)]
    assert inside.mean() > 0.6


def test_renderer_b_frames_train_the_reverse_direction():
    res = make_chunk(ChunkSpec("rcll2016", 3, towers=3, free=1, pasted=0,
                               source="skills.perception.light.unseen.compose:raycast_frames"))
    assert len(res.frames) == 4 and sum(1 for f in res.frames if f.tower_free) == 1
    assert len(res.pos) > 0 and len(res.crops) == len(res.states)
