"""Tags and lights of the robot's camera, from the detectors or the backend.

:class:`CameraPerception` runs the detectors on ``backend.camera_image()``:
ArUco tags (pose by solvePnP, upright disambiguation from the camera's
extrinsics) and the signal towers (:func:`.light.physical.default_reader`),
searched where each station tag in view says its tower must be
(:func:`.light.region.tower_region`) and, if ``full_frame_lights``, in the
whole frame when no tag is in view.  Light
detections found through a tag carry that tag's id.  A tower is read through
a tag only when the tag's pose puts all of it in the image and the camera
sees enough of its lowest lamp over the station
(:func:`.light.region.tower_readable`): a tower hidden in part is read as if
its hidden lamps were dark, and sure of it.

:func:`make_tag_source` picks the source by a setting, not by code in the
skills: ``"auto"`` takes the backend's own detections when it has the
``DETECTIONS`` capability (the simulator's oracle) and the detectors
otherwise; ``"oracle"`` and ``"camera"`` force one.  Both return
:class:`rll_bt.backend.Detections` from ``detections()``.
"""
from __future__ import annotations

import logging

import numpy as np

from rll_bt.backend import Backend, BackendError, Capability, CapabilityError, Detections, LightDetection
from rll_bt.rules import Profile

from ..machines import BackendTagSource as OracleSource
from .light.region import tower_readable, tower_region
from .tags import TagDetector

log = logging.getLogger(__name__)

MODES = ("auto", "oracle", "camera")


class CameraPerception:
    """A tag source running the detectors on the backend's camera frames."""

    #: its light readings carry the reader's class probabilities, read view by view
    #: (``skills.exploration.light_views``); the exploration reads towers from where they show whole
    light_views = True

    def __init__(self, backend: Backend, profile: Profile, reader=None, camera: str = "front",
                 full_frame_lights: bool = False, read_lights: bool = True, min_lamp_visible: float = 0.15):
        self.backend = backend
        self.profile = profile
        self.camera = camera
        self.tags = TagDetector(profile.tag_size, valid_ids=set(profile.all_tag_ids))
        self._reader = reader
        self.read_lights = read_lights
        self.full_frame_lights = full_frame_lights
        self.min_lamp_visible = min_lamp_visible     # share of the lowest lamp seen over its station
        self._last: tuple[float, Detections] | None = None
        self._last_image = None

    @property
    def reader(self):
        if self._reader is None:
            from .light.physical import default_reader
            self._reader = default_reader()
        return self._reader

    def detections(self) -> Detections | None:
        try:
            frame = self.backend.camera_image(self.camera)
        except (CapabilityError, BackendError) as exc:
            log.debug("no camera frame: %s", exc)
            return None
        if frame is None:
            return None
        if self._last is not None and self._last[0] == frame.stamp:
            return self._last[1]
        if self._last is not None and self._last_image is frame.image:
            # the very same image as last time (a camera that hands out its last frame while
            # nothing in view changed): the same detections, stamped now
            last = self._last[1]
            dets = Detections(frame.stamp, last.tags, last.lights, frame.extrinsics)
        else:
            dets = self.process(frame)
        self._last = (frame.stamp, dets)
        self._last_image = frame.image
        return dets

    def process(self, frame) -> Detections:
        """Tags and lights of one :class:`~rll_bt.backend.CameraImage`."""
        up = frame.extrinsics.rotation().T @ np.array([0.0, 0.0, 1.0])
        tags = self.tags.detect(frame.image, frame.intrinsics, frame.camera, up=up)
        lights: list[LightDetection] = []
        if self.read_lights:
            seen_boxes = []
            for tag in tags:
                owner = self.profile.machine_for_tag(tag.tag_id)
                if owner is None:
                    continue
                where = tower_region(tag, owner[1], self.profile.mps, frame.intrinsics)
                if where is None or not tower_readable(tag, owner[1], self.profile.mps, frame.intrinsics,
                                                       frame.extrinsics.position[2], self.min_lamp_visible):
                    continue
                region, height = where
                for d in self.reader.read(frame.image, region=region, tower_height=height,
                                          camera=frame.camera)[:1]:
                    if any(_same(d.box, b) for b in seen_boxes):
                        continue
                    seen_boxes.append(d.box)
                    lights.append(LightDetection(d.box, d.state, d.score, d.probabilities, d.camera,
                                                 tag_id=tag.tag_id))
            if not tags and self.full_frame_lights:
                lights.extend(self.reader.read(frame.image, camera=frame.camera))
        return Detections(frame.stamp, tuple(tags), tuple(lights), frame.extrinsics)


def _same(a, b) -> bool:
    from .light.hog import iou
    return iou(a, b) > 0.3


def make_tag_source(backend: Backend, profile: Profile, mode: str = "auto", **options):
    """The detections source for ``mode`` ("auto", "oracle" or "camera")."""
    if mode not in MODES:
        raise ValueError(f"perception mode must be one of {', '.join(MODES)}, not {mode!r}")
    has_oracle = Capability.DETECTIONS in backend.capabilities
    if mode == "oracle" or (mode == "auto" and has_oracle):
        if not has_oracle:
            raise CapabilityError(f"{backend.name}: no built-in perception (DETECTIONS) for mode 'oracle'")
        return OracleSource(backend, options.get("camera", "front"))    # skills.machines.BackendTagSource
    return CameraPerception(backend, profile, **options)
