import math

import cv2
import numpy as np
import pytest

from backends.sim import SimBackend
from backends.sim.sensors import camera_model, camera_pose, project
from rll_bt.backend import Capability, CapabilityError, Pose2D
from rll_bt.rules import ROBOT


def facing(station, side, distance, lateral=0.0):
    """Robot pose ``distance`` m (centre to face) in front of a station face, looking at it."""
    sign = 1.0 if side == "input" else -1.0
    m = station.profile.mps
    x, y, _ = station.to_world(sign * (m.depth / 2 + distance), m.belt_offset_y + lateral)
    return Pose2D(x, y, station.pose.theta + (math.pi if sign > 0 else 0.0))


def test_laser_sees_a_station_face_at_the_right_range(world):
    st = world.station("C-CS1")
    bot = SimBackend(world, ("CYAN", 1), pose=facing(st, "output", 1.2), laser_noise=0.005)
    scan = bot.laser_scan()
    mid = int(np.argmin(np.abs(scan.angles)))
    expected = 1.2 - ROBOT.laser_mount[0]
    assert scan.ranges[mid] == pytest.approx(expected, abs=0.03)
    assert len(scan.ranges) == 240 and scan.angle_min == pytest.approx(-ROBOT.laser_fov / 2)
    assert np.all(scan.ranges[np.isfinite(scan.ranges)] >= scan.range_min)
    # its own body does not show: no reading closer than the body edge behind the mount
    assert np.nanmin(scan.ranges) > 0.3


def test_laser_sees_other_robots_and_noise_is_configurable(empty_world):
    w = empty_world
    bot = SimBackend(w, ("CYAN", 1), pose=Pose2D(-1.0, 3.0, 0.0), laser_noise=0.0)
    SimBackend(w, ("CYAN", 2), pose=Pose2D(1.0, 3.0, 0.0))
    scan = bot.laser_scan()
    mid = int(np.argmin(np.abs(scan.angles)))
    assert scan.ranges[mid] == pytest.approx(2.0 - ROBOT.radius - ROBOT.laser_mount[0], abs=1e-3)
    # rate limited to 10 Hz: the same scan until 0.1 s have passed
    w.step(0.05)
    assert bot.laser_scan() is scan
    w.step(0.05)
    assert bot.laser_scan() is not scan


def test_oracle_sees_tag_and_light_in_view(world):
    st = world.station("C-RS1")
    world.set_lights("C-RS1", green="ON", red="ON")
    bot = SimBackend(world, ("CYAN", 1), pose=facing(st, "input", 1.5), dropout=0.0)
    assert Capability.DETECTIONS in bot.capabilities
    det = bot.detections()
    tag = min(det.tags, key=lambda t: t.tvec[2])       # other stations' tags may be in view too
    assert tag.tag_id == st.tag_ids[0]
    assert st.tag_ids[1] not in {t.tag_id for t in det.tags}     # the far face is hidden
    assert tag.tvec[2] == pytest.approx(1.5 - ROBOT.camera_mount[0], abs=0.1)
    assert len(tag.corners) == 4
    lights = [li for li in det.lights if li.tag_id == st.tag_ids[0]]
    assert len(lights) == 1 and lights[0].state == 1 + 4
    assert lights[0].lights == {"green": True, "yellow": False, "red": True}


def test_oracle_respects_range_fov_and_occlusion(world):
    st = world.station("C-RS1")
    bot = SimBackend(world, ("CYAN", 1), pose=facing(st, "input", 1.5))
    assert st.tag_ids[0] in {t.tag_id for t in bot.detections().tags}
    far = facing(st, "input", ROBOT.camera_range + 0.5)
    world.teleport("CYAN", 1, far)
    assert st.tag_ids[0] not in {t.tag_id for t in bot.detections().tags}
    turned = facing(st, "input", 1.5)
    world.teleport("CYAN", 1, Pose2D(turned.x, turned.y, turned.theta + math.pi / 2))
    assert st.tag_ids[0] not in {t.tag_id for t in bot.detections().tags}
    world.teleport("CYAN", 1, facing(st, "input", 2.0))
    blocker = facing(st, "input", 1.0)
    SimBackend(world, ("CYAN", 2), pose=blocker)
    assert st.tag_ids[0] not in {t.tag_id for t in bot.detections().tags}


def test_oracle_dropout_and_blink_phase(make_world):
    w = make_world("rcll2016", seed=3)
    st = w.station("C-RS1")
    bot = SimBackend(w, ("CYAN", 1), pose=facing(st, "input", 1.5), dropout=1.0)
    assert bot.detections().tags == () and bot.detections().lights == ()
    other = SimBackend(w, ("CYAN", 2), pose=facing(st, "input", 1.5, lateral=0.3))
    w.set_lights("C-RS1", yellow="BLINK")
    w.step(0.0625)                          # sample mid-phase
    states = []
    for _ in range(8):                      # 2 Hz: on for 0.25 s, off for 0.25 s
        states.append([li.state for li in other.detections().lights if li.tag_id == st.tag_ids[0]][0])
        w.step(0.125)
    assert states == [2, 2, 0, 0, 2, 2, 0, 0]


def test_tag_noise_perturbs_pose(world):
    st = world.station("C-RS1")
    quiet = SimBackend(world, ("CYAN", 1), pose=facing(st, "input", 1.5), tag_noise_pos=0.0, tag_noise_rot=0.0)
    noisy = SimBackend(world, ("CYAN", 2), pose=facing(st, "input", 1.5), tag_noise_pos=0.05, tag_noise_rot=0.1)
    world.teleport("CYAN", 1, facing(st, "input", 1.5))
    a = quiet.detections().tags[0]
    b = noisy.detections().tags[0]
    assert a.tvec != pytest.approx(b.tvec, abs=1e-4)
    # the noise-free pose puts the tag straight ahead, facing the camera
    rot, _ = cv2.Rodrigues(np.array(a.rvec))
    assert rot[:, 2] @ np.array([0, 0, -1.0]) == pytest.approx(1.0, abs=1e-6)


@pytest.fixture
def rendered(make_world):
    return make_world("rcll2016", seed=3, perception="rendered")


def test_rendered_mode_has_no_oracle(rendered):
    bot = SimBackend(rendered, ("CYAN", 1))
    assert Capability.DETECTIONS not in bot.capabilities
    with pytest.raises(CapabilityError):
        bot.detections()


@pytest.mark.parametrize("side", ["input", "output"])
def test_rendered_image_shows_the_right_tag(rendered, side):
    st = rendered.station("M-CS2")
    bot = SimBackend(rendered, ("CYAN", 1), pose=facing(st, side, 1.1))
    img = bot.camera_image()
    assert img.image.shape == (240, 320, 3) and img.image.dtype == np.uint8
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_ARUCO_ORIGINAL))
    corners, ids, _ = detector.detectMarkers(cv2.cvtColor(img.image, cv2.COLOR_BGR2GRAY))
    assert ids is not None and st.tag_id(side) in ids.ravel().tolist()
    # the marker is upright: the first corner is the top-left one
    c = corners[ids.ravel().tolist().index(st.tag_id(side))][0]
    assert c[0][0] < c[1][0] and c[0][1] < c[3][1]


def test_rendered_image_shows_the_light_state(rendered):
    st = rendered.station("M-CS2")
    rendered.set_lights("M-CS2", green="ON", yellow="OFF", red="ON")
    bot = SimBackend(rendered, ("CYAN", 1), pose=facing(st, "output", 1.0, lateral=-0.2),
                     camera_width=640, camera_height=480, camera_pitch=-0.3)
    img = bot.camera_image().image.astype(int)
    intr, extr = camera_model(bot.robot)
    eye, rot = camera_pose(bot.robot, extr)
    px = {}
    for i, name in enumerate(("green", "yellow", "red")):
        (u, v), = project(np.array([st.tower_point(i)]), eye, rot, intr)[0]
        assert 0 <= u < 640 and 0 <= v < 480
        b, g, r = img[int(round(v)) - 1:int(round(v)) + 2, int(round(u)) - 1:int(round(u)) + 2].reshape(-1, 3).mean(0)
        px[name] = (r, g, b)
    r, g, b = px["green"]
    assert g > 120 and g > r + 60 and g > b + 60
    r, g, b = px["red"]
    assert r > 120 and r > g + 60 and r > b + 60
    # the unlit yellow segment is tinted plastic: yellow, but far darker than a lit light
    r, g, b = px["yellow"]
    assert r > b + 30 and g > b + 25
    assert max(px["yellow"]) < 0.5 * max(px["red"])
