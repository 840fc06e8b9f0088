"""Camera views of the world (a mixin of :class:`backends.sim.world.World`).

- ``world.lighting`` / ``world.set_lighting(lighting=None, **changes)``: the
  hall's light and the camera settings (:class:`backends.sim.render.Lighting`;
  colour temperature, direction, intensity, exposure...), used by every view;
- ``world.render_view(eye, rot, intrinsics, lighting=None)`` ->
  :class:`backends.sim.render.View` (BGR image and segmentation) from any
  camera pose: ``eye`` field frame (metres), ``rot`` optical-frame axes in
  the field frame;
- ``world.camera_image(robot, camera)``: the robot's camera frame (at most
  ``camera_rate`` new frames per second), rendered
  at full resolution where stations can be detected and reused while
  nothing in view changes (:mod:`.sparse`; ``world.sparse_camera = False``
  renders every frame whole);
- ``world.hall``: the hall around the field (walls, ceiling, floor), built
  on the first view (oracle-only games never pay for it);
  ``world.hall.restyle(rng)`` gives it other textures;
- ``world.tower_links(machine)``: the body links of a station's signal tower,
  for labelling views by their segmentation; ``world.backdrop_bodies()``:
  the hall's bodies (pixels a compositor may replace);
- ``world.set_tower_look(unlit=None, emission=None)``: the colour of unlit
  segments (RGBA 0..1 per light) and the linear emission of lit ones (RGB
  per light, above 1 saturates), for every station.

Lit signal-light segments are emitters in every view (see :mod:`.render`).
"""
from __future__ import annotations

import numpy as np

from rll_bt.backend import CameraImage

from . import sensors, sparse
from .fieldgeom import floor_rect
from .hall import Hall
from .render import EMISSION, Lighting, View, render_view, seg_value


class CameraViews:
    """Needs ``cid``, ``seed``, ``profile``, ``stations``, ``time``,
    ``blink_hz`` and ``_sync_bodies``/``_show_lights`` of the world."""

    _lighting: Lighting | None = None
    _hall: Hall | None = None
    _emission: dict[str, tuple[float, float, float]] | None = None
    texture_dir: str | None = None
    sparse_camera: bool = True

    @property
    def lighting(self) -> Lighting:
        return self._lighting or Lighting()

    def set_lighting(self, lighting: Lighting | None = None, **changes) -> Lighting:
        """Set the lighting (a :class:`Lighting`, then field ``changes``); returns it."""
        self._lighting = (lighting or self.lighting).with_options(**changes)
        return self._lighting

    @property
    def hall(self) -> Hall:
        if self._hall is None:
            self._hall = Hall(self.cid, floor_rect(self.profile), self.seed, self.texture_dir)
        return self._hall

    def tower_links(self, machine: str) -> set[int]:
        return set(self.station(machine).tower_links)

    def backdrop_bodies(self) -> list[int]:
        return list(self.hall.bodies)

    def set_tower_look(self, unlit: dict[str, tuple] | None = None,
                       emission: dict[str, tuple[float, float, float]] | None = None) -> None:
        """See the module; ``None`` leaves a part as it is."""
        if unlit:
            for st in self.stations.values():
                st.set_unlit_colours(self.cid, unlit)
        if emission:
            self._emission = {**(self._emission or EMISSION), **{c.upper(): tuple(v) for c, v in emission.items()}}

    def _emitters(self) -> dict[int, tuple[float, float, float]]:
        table = self._emission or EMISSION
        out = {}
        for st in self.stations.values():
            for link, colour in st.lit_links().items():
                out[seg_value(st.body, link)] = table[colour]
        return out

    def render_view(self, eye, rot: np.ndarray, intrinsics, lighting: Lighting | None = None,
                    window: tuple[int, int, int, int] | None = None, stations=None) -> View:
        """A view from any camera pose (see the module); ``window`` (x, y, w, h)
        renders only that part of the image; ``stations`` (names), when given,
        are the only stations drawn (the others cannot show in this view)."""
        self.hall                                   # noqa: B018  (built on the first view)
        self._sync_bodies()
        self._show_lights()
        if not self.gui:                            # a window on the screen would flicker
            for st in self.stations.values():
                st.set_visible(self.cid, stations is None or st.name in stations)
        return render_view(self.cid, eye, rot, intrinsics, lighting or self.lighting, self._emitters(), window)

    def camera_image(self, robot, camera: str = "front"):
        """The robot's camera frame (one per robot per sim instant, and at most
        ``camera_rate`` a second)."""
        last = robot.last_image
        rate = robot.config.camera_rate
        if last is not None and last.camera == camera and (
                last.stamp == self.time or (rate and 0.0 <= self.time - last.stamp < 1.0 / rate - 1e-9)):
            return last
        intr, extr = sensors.camera_model(robot)
        self._sync_bodies()
        eye, rot = sensors.camera_pose(robot, extr)
        if self.sparse_camera:
            robot.camera_frame = sparse.sparse_frame(self, robot, eye, rot, intr, robot.camera_frame)
            image = robot.camera_frame[1]
        else:
            image = self.render_view(eye, rot, intr).image
        robot.last_image = CameraImage(self.time, image, intr, extr, camera)
        return robot.last_image
