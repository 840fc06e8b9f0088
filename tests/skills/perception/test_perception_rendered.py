"""Perception on images rendered by the PyBullet world, against the world's truth:
station tags decode to their ids and give the station's pose; the default
light reader reads the rendered tower's state through the tag-given region."""
import math

import numpy as np
import pytest

from backends.sim import World
from rll_bt.backend import Pose2D, wrap_angle
from skills.perception.light.physical import default_reader
from skills.perception.source import CameraPerception
from skills.perception.tags import MachineTracker, TagDetector

STATION = "C-RS1"


@pytest.fixture(scope="module")
def world():
    with World("rcll2016", seed=4, perception="rendered") as w:
        w.add_robot("CYAN", 1, camera_width=640, camera_height=480)
        yield w


@pytest.fixture(scope="module")
def reader():
    """What games read lights with (:func:`default_reader`)."""
    return default_reader()


def look_at_face(world, name, side, distance, off_deg):
    """Put the robot so its camera is ``distance`` m in front of the tag on
    ``side``, ``off_deg`` off the face normal, looking at the tag."""
    st = world.station(name)
    centre, frame = st.tag_frame(side)
    a = math.atan2(frame[1, 2], frame[0, 2]) + math.radians(off_deg)
    cx, cy = centre[0] + distance * math.cos(a), centre[1] + distance * math.sin(a)
    heading = math.atan2(centre[1] - cy, centre[0] - cx)
    world.teleport("CYAN", 1, Pose2D(cx - 0.2 * math.cos(heading), cy - 0.2 * math.sin(heading), heading))
    world.step(0.02)
    return world.camera_image(world.robot("CYAN", 1))


@pytest.mark.parametrize("side", ["input", "output"])
def test_station_tag_gives_its_id_and_the_station_pose(world, side):
    prof = world.profile
    st = world.station(STATION)
    detector = TagDetector(prof.tag_size, valid_ids=set(prof.all_tag_ids))
    tracker = MachineTracker(prof)
    for distance, off in ((0.9, -20), (1.4, 10), (2.0, 25)):
        img = look_at_face(world, STATION, side, distance, off)
        up = img.extrinsics.rotation().T @ np.array([0.0, 0.0, 1.0])
        tags = list(detector.detect(img.image, img.intrinsics, up=up))
        assert st.tag_id(side) in [t.tag_id for t in tags]
        tag = next(t for t in tags if t.tag_id == st.tag_id(side))
        assert tracker.add(tag, img.extrinsics, world.robot_pose("CYAN", 1)) == STATION
    est = tracker.estimate(STATION)
    assert est.pose.distance_to(st.pose) < 0.05
    assert abs(math.degrees(wrap_angle(est.pose.theta - st.pose.theta))) < 4.0
    assert est.zone == st.zone and est.rotation_deg == st.rotation % 360
    assert est.sides == {side.upper()}


@pytest.mark.parametrize("state", [0, 1, 2, 4, 5, 7])
def test_light_state_of_a_rendered_tower(world, reader, state):
    names = {"green": bool(state & 1), "yellow": bool(state & 2), "red": bool(state & 4)}
    world.set_lights(STATION, **{k: "ON" if v else "OFF" for k, v in names.items()})
    img = look_at_face(world, STATION, "output", 1.5, 15)
    assert world.visible_light_code(STATION) == state
    perception = CameraPerception(None, world.profile, reader=reader)
    dets = perception.process(img)
    out_tag = world.station(STATION).tag_id("output")
    assert out_tag in [t.tag_id for t in dets.tags]
    lights = [d for d in dets.lights if d.tag_id == out_tag]
    assert lights, "no tower found in the tag-given region"
    assert lights[0].state == state
    assert max(lights[0].probabilities) > 0.5


def test_service_on_the_sim_backend_reads_station_and_blinking_light(world, reader):
    """Camera mode: the rendered world has no oracle, so the service runs the
    detectors on the robot's camera frames, while the station blinks."""
    from rll_bt.backend import open_backend
    from skills.perception.service import PerceptionService
    from skills.perception.source import make_tag_source

    backend = open_backend("sim", world=world, robot=("CYAN", 1))
    source = make_tag_source(backend, world.profile)
    assert isinstance(source, CameraPerception)
    source._reader = reader
    seen = []
    svc = PerceptionService(source, world.profile, lambda: world.robot_pose("CYAN", 1), seen.append)
    world.set_lights(STATION, red="ON", green="BLINK")
    look_at_face(world, STATION, "output", 1.4, 10)
    for _ in range(16):
        world.step(0.1)
        svc.update()
    r = svc.report(STATION)
    st = world.station(STATION)
    assert r.pose.distance_to(st.pose) < 0.05 and r.zone == st.zone and r.rotation_deg == st.rotation % 360
    assert r.pattern.as_dict() == {"green": "BLINK", "yellow": "OFF", "red": "ON"}
    assert seen and seen[-1].machine == STATION


def test_the_same_frame_again_is_not_detected_again(world, reader):
    """A camera handing out its last frame (nothing in view changed) gets that
    frame's detections, stamped now, without running the detectors again."""
    from rll_bt.backend import open_backend
    backend = open_backend("sim", world=world, robot=("CYAN", 1))
    source = CameraPerception(backend, world.profile, reader=reader)
    # steady lights: a blinking one (left by another test of this module's world) changes the view
    world.set_lights(STATION, red="ON", yellow="OFF", green="OFF")
    look_at_face(world, STATION, "input", 1.2, 0)
    first = source.detections()
    assert first.tags
    calls = []
    source.process = lambda frame: calls.append(frame)
    world.step(0.1)
    again = source.detections()
    assert again.stamp == world.time and again.stamp > first.stamp
    assert again.tags == first.tags and again.lights == first.lights and not calls


def test_the_tag_is_found_at_every_distance_a_robot_lines_up_from():
    """Lining up, the robot stands about 0.62 m from the face, and the game's
    camera (320 x 240) then sees the tag at the bottom of its image.  Its white
    margin reaches the edge 0.600-0.615 m out: OpenCV's default border distance
    lost the tag there (rcll2016 seed 2 with rendered perception: four cap
    retrievals at C-CS2 failed with ALIGN_FAILED, 92 points instead of 406).
    Seen squarely 0.685 m out, the corners are an exact trapezoid that OpenCV's
    square-tag solver gives no pose for."""
    with World("rcll2016", seed=2, perception="rendered") as w:
        robot = w.add_robot("CYAN", 1)
        prof = w.profile
        detector = TagDetector(prof.tag_size, valid_ids=set(prof.all_tag_ids))
        for name in ("C-BS", "C-CS2"):
            st = w.station(name)
            centre, frame = st.tag_frame("input")
            nx, ny = frame[0, 2], frame[1, 2]
            heading = math.atan2(-ny, -nx)
            for mm in range(575, 705, 5):
                d = mm / 1000
                w.teleport("CYAN", 1, Pose2D(centre[0] + d * nx, centre[1] + d * ny, heading))
                w.step(0.02)
                img = w.camera_image(robot)
                found = [t.tag_id for t in detector.detect(img.image, img.intrinsics)]
                assert found == [st.tag_id("input")], f"{name} at {d:.3f} m from its face: {found}"
