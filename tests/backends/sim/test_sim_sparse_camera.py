"""A robot's camera frame rendered where something can be detected
(:mod:`backends.sim.sparse`): what the detectors find in it is what they
find in the whole view rendered at full resolution, a frame nothing in
view changed is handed out again, and a station hidden for a render keeps
its colours."""
import math

import numpy as np
import pytest

from backends.sim import World, sensors
from backends.sim.sparse import detail_range, scene, station_windows
from rll_bt.backend import Pose2D
from skills.perception.tags import TagDetector

STATION = "C-RS1"


@pytest.fixture(scope="module")
def world():
    with World("rcll2016", seed=4, perception="rendered") as w:
        w.add_robot("CYAN", 1)
        w.add_robot("CYAN", 2, pose=Pose2D(-5.0, 5.0, 0.0))
        yield w


def face(world, side="output", distance=1.2, off_deg=10.0, number=1):
    """Put robot ``number`` ``distance`` m in front of ``STATION``'s tag on ``side``, looking at it."""
    st = world.station(STATION)
    centre, frame = st.tag_frame(side)
    a = math.atan2(frame[1, 2], frame[0, 2]) + math.radians(off_deg)
    cx, cy = centre[0] + distance * math.cos(a), centre[1] + distance * math.sin(a)
    heading = math.atan2(centre[1] - cy, centre[0] - cx)
    world.teleport("CYAN", number, Pose2D(cx - 0.2 * math.cos(heading), cy - 0.2 * math.sin(heading), heading))
    world.step(0.02)
    return world.robot("CYAN", number)


def whole_and_sparse(world, robot):
    intr, extr = sensors.camera_model(robot)
    eye, rot = sensors.camera_pose(robot, extr)
    robot.camera_frame = None
    sparse = world.camera_image(robot).image
    whole = world.render_view(eye, rot, intr).image
    return whole, sparse, intr, extr


def test_a_window_is_pixel_for_pixel_the_whole_view(world):
    robot = face(world)
    intr, extr = sensors.camera_model(robot)
    eye, rot = sensors.camera_pose(robot, extr)
    whole = world.render_view(eye, rot, intr)
    for window in ((100, 40, 120, 150), (0, 0, 37, 23), (250, 200, 70, 40)):
        x, y, w, h = window
        part = world.render_view(eye, rot, intr, window=window)
        assert part.image.shape == (h, w, 3)
        assert np.array_equal(part.image, whole.image[y:y + h, x:x + w])
        assert np.array_equal(part.seg, whole.seg[y:y + h, x:x + w])


@pytest.mark.parametrize("distance,off", [(0.8, -15.0), (1.3, 10.0), (2.2, 25.0)])
def test_tags_in_a_sparse_frame_are_those_of_the_whole_view(world, distance, off):
    robot = face(world, distance=distance, off_deg=off)
    whole, sparse, intr, extr = whole_and_sparse(world, robot)
    tags = TagDetector(world.profile.tag_size, valid_ids=set(world.profile.all_tag_ids))
    up = extr.rotation().T @ np.array([0.0, 0.0, 1.0])
    a = {t.tag_id: t for t in tags.detect(whole, intr, up=up)}
    b = {t.tag_id: t for t in tags.detect(sparse, intr, up=up)}
    assert world.station(STATION).tag_id("output") in a
    assert set(a) == set(b)
    for k in a:
        assert np.allclose(a[k].tvec, b[k].tvec, atol=0.01)
    # the tower's window holds the tower exactly as the whole view shows it
    st = world.station(STATION)
    top = np.array(st.tower_point(2)) + [0, 0, st.profile.mps.tower_segment / 2]
    bottom = np.array(st.tower_point(0)) - [0, 0, st.profile.mps.tower_segment / 2]
    eye, rot = sensors.camera_pose(robot, extr)
    uv, _ = sensors.project(np.array([top, bottom]), eye, rot, intr)
    x = int(round(uv[:, 0].mean()))
    y0, y1 = int(math.floor(uv[:, 1].min())), int(math.ceil(uv[:, 1].max()))
    assert np.array_equal(whole[max(0, y0):y1, max(0, x - 2):x + 3], sparse[max(0, y0):y1, max(0, x - 2):x + 3])


def test_only_stations_near_enough_for_a_tag_to_be_read_get_windows(world):
    robot = face(world, distance=1.2)
    intr, extr = sensors.camera_model(robot)
    eye, rot = sensors.camera_pose(robot, extr)
    far = detail_range(intr, world.profile.tag_size)
    assert 3.0 < far < 4.5                               # 320 x 240: a 13.5 cm tag 10 px wide
    windows, shown = station_windows(scene(world), eye, rot, intr, far)
    assert STATION in [st.name for st in shown]
    assert all(math.hypot(st.pose.x - eye[0], st.pose.y - eye[1]) < far + 1.0 for st in shown)
    assert windows and sum(w * h for _, _, w, h, _ in windows) < 0.6 * intr.width * intr.height


def test_a_frame_nothing_in_view_changed_is_handed_out_again(world):
    robot = face(world, distance=1.2)
    first = world.camera_image(robot).image
    world.step(0.1)
    again = world.camera_image(robot)
    assert again.image is first and again.stamp == world.time
    world.set_lights(STATION, red="ON")                  # a light in view changes
    world.step(0.1)
    lit = world.camera_image(robot).image
    assert lit is not first
    world.step(0.1)
    assert world.camera_image(robot).image is lit
    face(world, distance=1.25)                           # the camera moves
    assert world.camera_image(robot).image is not lit
    world.set_lights(STATION, red="OFF")


def test_the_camera_rate_limits_new_frames(make_world):
    w = make_world("rcll2016", seed=4, perception="rendered")
    robot = w.add_robot("CYAN", 1, camera_rate=5.0)
    first = w.camera_image(robot)
    w.teleport("CYAN", 1, Pose2D(robot.pose.x + 0.3, robot.pose.y, robot.pose.theta))
    w.step(0.1)
    assert w.camera_image(robot) is first                # 0.1 s after a frame: still that frame
    w.step(0.1)
    assert w.camera_image(robot).stamp == pytest.approx(w.time)


def test_a_station_hidden_for_a_render_keeps_its_colours(world):
    robot = face(world, distance=1.0)
    intr, extr = sensors.camera_model(robot)
    eye, rot = sensors.camera_pose(robot, extr)
    st = world.station(STATION)
    world.set_lights(STATION, green="ON")
    before = world.render_view(eye, rot, intr).image
    st.set_visible(world.cid, False)
    gone = world.render_view(eye, rot, intr, stations=set()).image
    assert not np.array_equal(gone, before)
    world.set_lights(STATION, green="OFF", yellow="ON")   # changed while hidden
    world.step(0.02)
    world.render_view(eye, rot, intr, stations=set())
    after = world.render_view(eye, rot, intr).image
    world.set_lights(STATION, green="ON", yellow="OFF")
    world.step(0.02)
    assert np.array_equal(world.render_view(eye, rot, intr).image, before)
    assert not np.array_equal(after, before)


def test_an_empty_view_is_not_rendered_again_for_small_moves(world):
    robot = world.robot("CYAN", 2)
    f = world.profile.field
    world.teleport("CYAN", 2, Pose2D(f.x_min + 0.5, f.y_min + 0.5, math.radians(-135)))   # into a corner
    world.step(0.02)
    first = world.camera_image(robot).image
    world.teleport("CYAN", 2, Pose2D(f.x_min + 0.55, f.y_min + 0.5, math.radians(-134)))
    world.step(0.1)
    assert world.camera_image(robot).image is first
    world.step(1.2)                                      # but not for ever
    assert world.camera_image(robot).image is not first


def test_a_window_narrower_than_its_divisor_is_drawn_at_full_resolution(world, monkeypatch):
    """A window of 2 px at divisor 4 once made an empty render and cv2.resize raised out of the
    hardware game's world (seed 2)."""
    from backends.sim import sparse
    robot = face(world, distance=2.2)
    real = sparse.station_windows

    def sliver(*args, **kw):
        windows, shown = real(*args, **kw)
        return [(100, 40, 2, 30, 4), (10, 10, 30, 3, 4)] + list(windows), shown
    monkeypatch.setattr(sparse, "station_windows", sliver)
    robot.camera_frame = None
    image = world.camera_image(robot).image
    intr, _ = sensors.camera_model(robot)
    assert image.shape == (intr.height, intr.width, 3)
