"""The robot's camera: :class:`~.grabber.CameraGrabber` (V4L2 device, video
file or stream URL through ``cv2.VideoCapture``, newest frame with its time
stamp), intrinsics from a calibration file (:mod:`.calibration`), and
:class:`~.mjpeg.MjpegServer`, the emulated camera (MJPEG over HTTP)."""
from .calibration import CalibrationError, load_intrinsics
from .grabber import CameraGrabber, CameraStats

__all__ = ["CalibrationError", "CameraGrabber", "CameraStats", "load_intrinsics"]
