"""What the robot knows and sees of the stations: the interface between the
skills and perception.

- :class:`MachineObservation`: one sighting of a station (its pose in the
  field frame, the side whose tag was seen, the light state if read).
- :class:`MachineMap`: where each station is believed to be.  Fed by the
  team server's machine map (through the agent), by perception's tracker,
  or by :meth:`MachineMap.observe`; confirmed stations go into the
  :class:`~skills.maps.FieldMap` as obstacles.
- :class:`TagSource`: the latest tag sightings of the front camera.
  :class:`BackendTagSource` reads ``backend.detections()`` (the simulation
  oracle); perception supplies its own source for rendered or real images
  (``set_tag_source``).  Either way the skills get ``Detections``.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

from rll_bt.backend import Backend, BackendError, CapabilityError, Detections, Pose2D

from .maps import FieldMap


@dataclass(frozen=True)
class MachineObservation:
    """A station as seen.  ``pose`` is the machine centre in the field frame
    (machine x axis from output to input, see ``rll_bt.rules.geometry``);
    ``light_state`` 0..7 (green 1, yellow 2, red 4) when the light was read;
    ``light_confidence`` how sure that reading is (None: as sure as the
    sighting, ``confidence``) and ``light_view`` which of the robot's views
    of the tower it comes from (None: a reading handed over as exact, e.g.
    by the simulator's oracle; see :mod:`skills.exploration.light_views`)."""
    machine: str
    pose: Pose2D | None
    stamp: float
    side: str | None = None            # "INPUT" / "OUTPUT" of the tag seen
    tag_id: int | None = None
    zone: int | None = None
    light_state: int | None = None
    confidence: float = 1.0
    light_confidence: float | None = None
    light_view: int | None = None


ObservationSink = Callable[[MachineObservation], None]


@runtime_checkable
class TagSource(Protocol):
    def detections(self) -> Detections | None:
        """Tags (and lights) of the latest camera frame, or None when none."""


class BackendTagSource:
    """Tags from the backend's own perception (``Capability.DETECTIONS``)."""

    def __init__(self, backend: Backend, camera: str = "front"):
        self.backend = backend
        self.camera = camera
        self.available = True

    def detections(self) -> Detections | None:
        if not self.available:
            return None
        try:
            return self.backend.detections(self.camera)
        except CapabilityError:
            self.available = False
            return None
        except BackendError:
            return None


class MachineMap:
    """Believed station poses by machine name ("C-CS1").  With a
    ``field_map``, every pose set here is also added to it as an obstacle,
    so localisation and planning use the station at once."""

    def __init__(self, field_map: FieldMap | None = None, mps=None):
        self._poses: dict[str, Pose2D] = {}
        self._observations: dict[str, MachineObservation] = {}
        self.field_map = field_map
        self.mps = mps
        self._listeners: list[ObservationSink] = []

    def set(self, machine: str, pose: Pose2D, confirm: bool = True) -> None:
        """Record a station's pose; ``confirm`` also puts it into the field map."""
        self._poses[machine] = pose
        if confirm and self.field_map is not None:
            if self.mps is None:
                self.field_map.add_station(machine, pose)
            else:
                self.field_map.add_station(machine, pose, self.mps)

    def get(self, machine: str) -> Pose2D | None:
        return self._poses.get(machine)

    def __contains__(self, machine: str) -> bool:
        return machine in self._poses

    def names(self) -> list[str]:
        return sorted(self._poses)

    def observe(self, obs: MachineObservation) -> None:
        """Keep the latest observation per machine and tell the listeners
        (the agent streams them to the team server)."""
        prev = self._observations.get(obs.machine)
        if prev is not None and obs.light_state is None and prev.light_state is not None:
            obs = replace(obs, light_state=prev.light_state, light_confidence=prev.light_confidence,
                          light_view=prev.light_view)
        self._observations[obs.machine] = obs
        for listener in list(self._listeners):
            listener(obs)

    def observation(self, machine: str) -> MachineObservation | None:
        return self._observations.get(machine)

    def observations(self) -> dict[str, MachineObservation]:
        return dict(self._observations)

    def subscribe(self, sink: ObservationSink) -> None:
        self._listeners.append(sink)
