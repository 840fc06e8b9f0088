"""Where the stations are for a robot whose team server sends no machine map.

An rll-bt team server tells its robots where the stations are
(``MachineMap``).  A team server that speaks only the league's messages
does not: like the league simulator's robots, the robot then finds the
stations itself, from

- what the refbox says on the team channel: ``MachineInfo`` names a
  station's zone (and, rcll2025, its rotation) once it is reported right,
  and for every station once the exploration time is over;
- what it saw: its own sightings (tag and pose), once ``min_confidence``
  sure.

A sighting's pose beats the refbox's zone; a zone with a rotation gives the
zone centre turned by the rotation (the 2025 field puts a station at its
zone's centre), a zone alone no pose (exploring the zone finds it).
:meth:`LocalMachines.known` is a :class:`~.machinemap.KnownMachines`, handed
to the skills like a team server's map.
"""
from __future__ import annotations

from ..backend import Pose2D
from ..rules import Profile, machine_team, machine_type, rotation_to_theta
from .machinemap import KnownMachine, KnownMachines


class LocalMachines:
    def __init__(self, profile: Profile, min_confidence: float = 0.5):
        self.profile = profile
        self.min_confidence = min_confidence
        self._refbox: dict[str, tuple[int, int | None]] = {}    # name -> (zone, rotation)
        self._seen: dict[str, tuple[Pose2D, int | None, float]] = {}   # name -> (pose, zone, confidence)
        self.version = 0

    def on_machine_info(self, msg) -> bool:
        """Take the zones (and rotations) a MachineInfo reveals; whether anything changed."""
        changed = False
        for m in msg.machines:
            if m.name not in self.profile.tags or not m.HasField("zone") or not m.zone:
                continue
            zone = int(m.zone)
            if zone not in self.profile.zones.all_zones:
                continue
            fields = m.DESCRIPTOR.fields_by_name
            rot = int(m.rotation) if "rotation" in fields and m.HasField("rotation") else None
            if self._refbox.get(m.name) != (zone, rot):
                self._refbox[m.name] = (zone, rot)
                changed = True
        if changed:
            self.version += 1
        return changed

    def on_sighting(self, name: str, pose: Pose2D | None, zone: int | None, confidence: float) -> bool:
        """Take one of the robot's own sightings; whether it changed the map."""
        if name not in self.profile.tags or pose is None or confidence < self.min_confidence:
            return False
        old = self._seen.get(name)
        if old is not None and old[0].distance_to(pose) < 0.05 and abs(old[2] - confidence) < 0.1:
            return False
        self._seen[name] = (pose, zone, float(confidence))
        self.version += 1
        return True

    def on_observations(self, messages) -> bool:
        """Take the robot's own sightings (``rllbt.MachineObservation`` messages of the
        observation feed; others are skipped); whether the map changed."""
        changed = False
        for m in messages:
            if m.DESCRIPTOR.name == "MachineObservation" and m.HasField("name") and m.HasField("pose"):
                p = m.pose.pose
                changed |= self.on_sighting(m.name.value, Pose2D(p.x, p.y, p.theta),
                                            int(m.zone.value) if m.HasField("zone") else None,
                                            float(m.pose.confidence))
        return changed

    def known(self) -> KnownMachines:
        out: dict[str, KnownMachine] = {}
        for name in sorted(set(self._refbox) | set(self._seen)):
            zone, rot = self._refbox.get(name, (None, None))
            seen = self._seen.get(name)
            pose, conf = None, 0.0
            if seen is not None:
                pose, conf = seen[0], seen[2]
                zone = zone if zone is not None else seen[1]
            elif zone is not None and rot is not None:
                cx, cy = self.profile.zone_centre(zone)
                pose, conf = Pose2D(cx, cy, rotation_to_theta(rot)), 1.0
            tags = self.profile.tag_ids(name)
            out[name] = KnownMachine(name, machine_type(name), machine_team(name), pose, zone, rot,
                                     tags[0], tags[1], conf)
        return KnownMachines(out, self.profile.name)
