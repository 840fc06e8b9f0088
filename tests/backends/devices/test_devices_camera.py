"""The camera grabber against an MJPEG stream over HTTP on loopback and a
video file; calibration files in both layouts."""
import math
import time

import cv2
import numpy as np
import pytest

from backends.devices.camera import CalibrationError, CameraGrabber, load_intrinsics
from backends.devices.camera.calibration import scaled, write_filestorage
from backends.devices.camera.mjpeg import MjpegServer
from rll_bt.backend import CameraExtrinsics, CameraIntrinsics


class Source:
    """Frames whose green value counts them (JPEG keeps a flat colour)."""

    def __init__(self):
        self.n = 0
        self.made = {}

    def __call__(self):
        self.n += 1
        img = np.zeros((240, 320, 3), np.uint8)
        img[:, :, 1] = (self.n * 20) % 250
        self.made[self.n] = time.monotonic()
        return img


@pytest.fixture
def stream():
    src = Source()
    server = MjpegServer(src, fps=15).start()
    yield server, src
    server.stop()


def test_frames_arrive_with_their_time_stamps_and_the_newest_is_kept(stream, wait_for):
    server, _src = stream
    extr = CameraExtrinsics((0.2, 0.0, 0.5), pitch=0.3)
    cam = CameraGrabber(server.url, extrinsics=extr, hfov=math.radians(60)).start(wait=10)
    try:
        assert wait_for(lambda: cam.stats().frames >= 10, 5)
        f = cam.latest()
        assert f.image.shape == (240, 320, 3) and f.extrinsics == extr and f.camera == "front"
        assert abs(f.stamp - time.monotonic()) < 0.5
        assert f.intrinsics == CameraIntrinsics.from_fov(320, 240, math.radians(60))
        assert 8 < cam.stats().rate < 25
        t0 = time.monotonic()
        for _ in range(100):
            cam.latest()
        assert time.monotonic() - t0 < 0.05            # never waits for the camera
    finally:
        cam.close()


def test_an_unplugged_camera_is_noticed_and_reopened(stream, wait_for):
    server, _ = stream
    cam = CameraGrabber(server.url, timeout=0.5, reopen_interval=0.2).start(wait=10)
    try:
        server.unplug(1.5)
        assert wait_for(lambda: not cam.healthy(0.4), 3)
        assert wait_for(lambda: cam.healthy(0.4), 10)
        assert cam.stats().connects >= 2
    finally:
        cam.close()


def test_a_silent_stream_does_not_hang_the_grabber(stream, wait_for):
    server, _ = stream
    cam = CameraGrabber(server.url, timeout=0.5, reopen_interval=0.2).start(wait=10)
    try:
        server.set_silent(True)
        assert wait_for(lambda: not cam.healthy(0.4), 3)
        server.set_silent(False)
        assert wait_for(lambda: cam.healthy(0.4), 10)
    finally:
        cam.close()


def test_a_video_file_plays_at_its_rate_and_loops(tmp_path, wait_for):
    path = str(tmp_path / "clip.avi")
    w = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 20, (160, 120))
    for i in range(10):
        w.write(np.full((120, 160, 3), i * 20, np.uint8))
    w.release()
    cam = CameraGrabber(path).start(wait=5)
    try:
        assert wait_for(lambda: cam.stats().frames >= 15, 5)      # more than the file holds: it looped
        assert cam.latest().image.shape == (120, 160, 3)
    finally:
        cam.close()


def test_calibration_files_in_both_layouts(tmp_path):
    intr = CameraIntrinsics(640, 480, 600.0, 610.0, 320.5, 240.5, (0.1, -0.2, 0.0, 0.0, 0.05))
    write_filestorage(tmp_path / "cv.yaml", intr)
    assert load_intrinsics(tmp_path / "cv.yaml") == intr
    (tmp_path / "ros.yaml").write_text(
        "image_width: 640\nimage_height: 480\ncamera_name: front\n"
        "camera_matrix: {rows: 3, cols: 3, data: [600, 0, 320.5, 0, 610, 240.5, 0, 0, 1]}\n"
        "distortion_model: plumb_bob\n"
        "distortion_coefficients: {rows: 1, cols: 5, data: [0.1, -0.2, 0, 0, 0.05]}\n")
    assert load_intrinsics(tmp_path / "ros.yaml") == intr
    half = scaled(intr, 320, 240)
    assert (half.fx, half.cx) == (300.0, 160.25)


@pytest.mark.parametrize("text,message", [
    ("image_width: 640\nimage_height: 480\n", "no camera_matrix"),
    ("image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [1, 2]}\n", "2 values"),
    ("[1, 2", "not YAML"),
])
def test_bad_calibration_files_say_what_is_wrong(tmp_path, text, message):
    (tmp_path / "c.yaml").write_text(text)
    with pytest.raises(CalibrationError, match=message):
        load_intrinsics(tmp_path / "c.yaml")
