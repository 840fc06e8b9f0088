"""The camera renderer: lit lights are emitters, unlit ones tinted plastic,
the tower's core shows in its borders, the hall fills the view, lighting is
settable; and the oracle's tag check looks at more than the centre ray."""
import math

import cv2
import numpy as np
import pytest

from backends.sim import SimBackend
from backends.sim.oracle import _clear
from backends.sim.render import Lighting, kelvin_rgb
from backends.sim.sensors import camera_model, camera_pose
from rll_bt.backend import CameraIntrinsics, Pose2D

STATION = "C-RS1"
INTR = CameraIntrinsics.from_fov(320, 240, 0.9)
HUE = {"GREEN": 60, "YELLOW": 25, "RED": 0}          # OpenCV hue, 0..180
LIGHTINGS = [Lighting(), Lighting(kelvin=3000, white_balance=3000, intensity=0.2, ambient=0.35, azimuth=2.5),
             Lighting(kelvin=6500, white_balance=6500, intensity=0.7, ambient=0.3, elevation=0.3, specular=0.2),
             Lighting(kelvin=3500, white_balance=5500, exposure=0.7)]


def look_at(eye, target):
    """Optical axes (x right, y down, z forward) as columns, field frame."""
    fwd = np.asarray(target, float) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    return np.column_stack([right, np.cross(fwd, right), fwd])


def tower_view(world, distance=0.9, lighting=None):
    st = world.station(STATION)
    centre, frame = st.tag_frame("output")
    target = np.array(st.tower_point(1))
    eye = np.array([centre[0] + distance * frame[0, 2], centre[1] + distance * frame[1, 2], 1.05])
    return world.render_view(eye, look_at(eye, target), INTR, lighting)


def link_mask(world, view, links):
    st = world.station(STATION)
    return (view.body == st.body) & np.isin(view.link, list(links))


def hsv(pixels):
    return cv2.cvtColor(pixels.reshape(-1, 1, 3).astype(np.uint8), cv2.COLOR_BGR2HSV).reshape(-1, 3)


@pytest.mark.parametrize("lighting", LIGHTINGS, ids=["default", "warm-dim", "cold-low-sun", "dark"])
def test_lit_lights_are_brighter_than_any_shaded_surface(world, lighting):
    st = world.station(STATION)
    world.set_lights(STATION, green="OFF", yellow="OFF", red="OFF")
    dark = tower_view(world, lighting=lighting).image.max(axis=2)
    world.set_lights(STATION, green="ON", yellow="ON", red="ON")
    view = tower_view(world, lighting=lighting)
    lit = link_mask(world, view, st.lit_links())
    assert lit.sum() > 100
    brightest_shaded = np.percentile(dark, 99.9)
    assert np.median(view.image.max(axis=2)[lit]) > brightest_shaded + 20


@pytest.mark.parametrize("lighting", LIGHTINGS, ids=["default", "warm-dim", "cold-low-sun", "dark"])
def test_an_unlit_segment_keeps_its_hue(world, lighting):
    st = world.station(STATION)
    world.set_lights(STATION, green="OFF", yellow="OFF", red="OFF")
    view = tower_view(world, lighting=lighting)
    for colour, link in st._light_links.items():
        px = hsv(view.image[link_mask(world, view, {link})])
        hue = np.median(px[:, 0].astype(float))
        off = min(abs(hue - HUE[colour]), 180 - abs(hue - HUE[colour]))
        assert off <= 12, (colour, hue)
        assert np.median(px[:, 1]) > 80, colour                 # coloured, not grey
        assert np.median(px[:, 2]) < 200, colour                # and not glowing


def test_the_core_shows_between_the_segments(world):
    st = world.station(STATION)
    view = tower_view(world, distance=0.6)
    tower = link_mask(world, view, st.tower_links)
    rows = np.flatnonzero(tower.any(axis=1))
    assert len(rows) > 40
    # every row from the housing to the bottom segment is tower: no background in the borders
    assert np.all(tower[rows[0]:rows[-1] + 1].any(axis=1))


def test_the_hall_fills_the_view_behind_the_field(world):
    f = world.profile.field
    for eye, target in (((0.0, f.y_min + 0.5, 0.6), (0.0, f.y_max + 5, 1.0)),
                        ((f.x_min + 0.5, 2.0, 0.6), (f.x_max + 5, 3.0, 2.5))):
        view = world.render_view(np.array(eye), look_at(np.array(eye), target), INTR)
        assert (view.seg < 0).mean() == 0.0
        assert np.isin(view.body, world.backdrop_bodies()).mean() > 0.2


def test_lighting_colour_temperature_tints_the_scene(world):
    st = world.station(STATION)
    world.set_lights(STATION, green="OFF", yellow="OFF", red="OFF")
    ratios = []
    for kelvin in (3000, 8000):
        world.set_lighting(Lighting(), kelvin=kelvin, white_balance=5000)
        view = tower_view(world)
        cabinet = view.image[(view.body == st.body) & (view.link == -1)].astype(float)
        ratios.append(cabinet[:, 2].mean() / cabinet[:, 0].mean())        # red / blue
    world.set_lighting(Lighting())
    assert ratios[0] > 1.3 > ratios[1] * 1.1
    assert kelvin_rgb(3000)[2] < kelvin_rgb(6500)[2]
    with pytest.raises(ValueError):
        Lighting(exposure=-1.0)


def test_oracle_drops_a_tag_hidden_but_for_its_centre(world):
    """A robot's mast slid in front of a tag from the side: there is a
    position where the ray to the tag's centre is still free but the tag is
    no longer seen, because rays to its corners are blocked."""
    st = world.station(STATION)
    m = st.profile.mps
    x, y, _ = st.to_world(m.depth / 2 + 1.6, m.belt_offset_y)
    viewer = SimBackend(world, ("CYAN", 1), pose=Pose2D(x, y, st.pose.theta + math.pi), dropout=0.0)
    assert st.tag_ids[0] in {t.tag_id for t in viewer.detections().tags}
    eye, _ = camera_pose(viewer.robot, camera_model(viewer.robot)[1])
    centre, _ = st.tag_frame("input")
    SimBackend(world, ("CYAN", 2), pose=Pose2D(*st.to_world(3.0, 0.0)[:2], 0.0))
    centre_free_but_unseen = []
    for lateral in np.linspace(0.45, 0.0, 46):             # slide the blocker in from the side
        bx, by, _ = st.to_world(m.depth / 2 + 0.7, m.belt_offset_y + lateral)
        world.teleport("CYAN", 2, Pose2D(bx, by, st.pose.theta))
        seen = st.tag_ids[0] in {t.tag_id for t in viewer.detections().tags}   # (moves the bodies)
        centre_free = _clear(world.cid, viewer.robot, eye, [centre])[0]
        assert not (seen and not centre_free)
        centre_free_but_unseen.append(centre_free and not seen)
    assert any(centre_free_but_unseen)
