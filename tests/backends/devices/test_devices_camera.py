"""The camera grabber against an MJPEG stream over HTTP on loopback and a
video file; calibration files in both layouts."""
import math
import threading
import time

import cv2
import numpy as np
import pytest

from backends.devices.camera import CalibrationError, CameraGrabber, load_intrinsics
from backends.devices.camera.calibration import scaled, write_filestorage
from backends.devices.camera.mjpeg import MjpegServer
from rll_bt.backend import CameraExtrinsics, CameraIntrinsics


class Source:
    """Frames that say which they are: the n-th has green ``20 * (n % 12)`` and red
    ``20 * (n // 12 % 12)`` (JPEG keeps a flat colour); ``made[n]`` is when it was made."""

    def __init__(self):
        self.n = 0
        self.made = {}

    def __call__(self):
        self.n += 1
        self.made[self.n] = time.monotonic()
        img = np.zeros((240, 320, 3), np.uint8)
        img[:, :, 1] = 20 * (self.n % 12)
        img[:, :, 2] = 20 * (self.n // 12 % 12)
        return img

    def number(self, image) -> int:
        """Which frame ``image`` is: the newest made with its colours."""
        code = round(float(image[:, :, 2].mean()) / 20) * 12 + round(float(image[:, :, 1].mean()) / 20)
        return max(n for n in list(self.made) if n % 144 == code)


@pytest.fixture
def stream():
    src = Source()
    server = MjpegServer(src, fps=15).start()
    yield server, src
    server.stop()


def test_frames_arrive_with_their_time_stamps_and_the_newest_is_kept(stream, wait_for):
    server, src = stream
    extr = CameraExtrinsics((0.2, 0.0, 0.5), pitch=0.3)
    cam = CameraGrabber(server.url, extrinsics=extr, hfov=math.radians(60)).start(wait=120)
    try:
        assert wait_for(lambda: cam.stats().frames >= 10, 5)
        received = cam.stats().frames
        f = cam.latest()
        seen_by = time.monotonic()
        assert f.image.shape == (240, 320, 3) and f.extrinsics == extr and f.camera == "front"
        assert f.intrinsics == CameraIntrinsics.from_fov(320, 240, math.radians(60))
        # stamped on the host's clock when it arrived: after the frame was made, before the test had it
        n = src.number(f.image)
        assert src.made[n] <= f.stamp <= seen_by
        # the newest kept: frames come in the order they were made, so the n-th received is at least the n-th made
        assert n >= received
        later = wait_for(lambda: src.number(cam.latest().image) > n, 5)
        assert later and cam.latest().stamp > f.stamp
        # never waits for the camera: with the stream silent, the newest frame is still there at once
        server.set_silent(True)
        got = []
        reader = threading.Thread(target=lambda: got.extend(cam.latest() for _ in range(100)), daemon=True)
        reader.start()
        reader.join(timeout=120.0)                          # bounds a hang only
        assert len(got) == 100 and all(g is not None for g in got)
    finally:
        cam.close()


def test_an_unplugged_camera_is_noticed_and_reopened(stream, wait_for):
    server, _ = stream
    cam = CameraGrabber(server.url, timeout=0.5, reopen_interval=0.2).start(wait=120)
    try:
        server.unplug(1.5)
        assert wait_for(lambda: not cam.healthy(0.4), 3)
        assert wait_for(lambda: cam.healthy(0.4), 10)
        assert cam.stats().connects >= 2
    finally:
        cam.close()


def test_a_silent_stream_does_not_hang_the_grabber(stream, wait_for):
    server, _ = stream
    cam = CameraGrabber(server.url, timeout=0.5, reopen_interval=0.2).start(wait=120)
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
    cam = CameraGrabber(path).start(wait=120)
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


def test_a_frame_goes_out_when_it_is_there_not_a_period_later(wait_for):
    """The emulated camera's world renders on its own clock and the source has
    nothing new between renders: a frame that appears between the server's looks
    goes out at once (polled once a period, it waited up to 0.2 s at 5 fps, and
    tags seen while the robot turned put stations 0.3 m off)."""
    state = {"sparse": False, "pending": None, "sent": 0.0}

    def source():
        if state["sparse"] and state["pending"] is None:
            return None
        state["pending"], state["sent"] = None, time.monotonic()
        return np.full((240, 320, 3), 90, np.uint8)

    server = MjpegServer(source, fps=1.0)             # a look a second at most
    server.start()
    cam = CameraGrabber(server.url, hfov=math.radians(60), timeout=10.0).start(wait=120)
    try:
        assert wait_for(lambda: cam.stats().frames >= 2, 30)
        state["sparse"] = True
        delays = []
        for _ in range(3):
            before = cam.stats().frames
            # just after one of the server's looks (a second apart before this change)
            assert wait_for(lambda: time.monotonic() - state["sent"] >= 1.05, 10)
            made = time.monotonic()
            state["pending"] = made
            assert wait_for(lambda before=before: cam.stats().frames > before, 10)
            delays.append(cam.latest().stamp - made)
        assert max(delays) < 0.5, f"frames waited for the server's next look: {delays}"
    finally:
        cam.close()
        server.stop()


def test_a_frame_is_stamped_when_it_was_taken_not_when_it_arrived(wait_for):
    """The server says when each frame was taken (X-Timestamp): a frame of the world as
    it stood 0.3 s before it went out is stamped then (the robot's pose at that time is
    where the tags were seen from), not when it arrived."""
    taken = {}

    def source():
        now = time.monotonic()
        n = len(taken) + 1
        taken[n] = now - 0.3
        img = np.zeros((240, 320, 3), np.uint8)
        img[:, :, 1] = 20 * (n % 12)
        return img, taken[n]

    server = MjpegServer(source, fps=10.0).start()
    cam = CameraGrabber(server.url, hfov=math.radians(60)).start(wait=120)
    try:
        assert wait_for(lambda: cam.stats().frames >= 5, 30)
        f, arrived_by = cam.latest(), time.monotonic()
        n = max(k for k in list(taken) if k % 12 == round(float(f.image[:, :, 1].mean()) / 20))
        assert abs(f.stamp - taken[n]) < 0.02 and f.stamp < arrived_by - 0.25
    finally:
        cam.close()
        server.stop()


def test_a_capture_time_from_another_clock_is_not_used():
    cam = CameraGrabber("http://127.0.0.1:9/none.mjpg", latency=0.05)
    assert cam._stamp(100.0, time.time() - 0.1) == pytest.approx(99.9, abs=0.01)
    assert cam._stamp(100.0, time.time() - 3600.0) == pytest.approx(99.95)     # another machine's clock
    assert cam._stamp(100.0, time.time() + 5.0) == pytest.approx(99.95)
    assert cam._stamp(100.0, None) == pytest.approx(99.95)
