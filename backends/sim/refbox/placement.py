"""Random mirrored station placement (refbox-protocol §5), zone level.

Cyan machines go to distinct cyan zones (BS and DS to the profile's fixed
zones), each magenta twin to the mirror zone with the mirrored rotation
(:meth:`Profile.mirror_placement`), and then one RS and one CS, chosen at
random, swap zone and rotation between the teams.  A station stands at the
centre of its zone.  The PyBullet world has its own generator with free
positions inside the zone; this one serves the in-memory world.
"""
from __future__ import annotations

import random

from rll_bt.rules import CYAN, MAGENTA, machine_type, mirror_machine_name

from .world import StationPose


def generate_zones(profile, rng: random.Random) -> dict[str, tuple[int, int]]:
    """machine -> (zone, rotation in degrees) for both teams."""
    cyan = profile.machines(CYAN)
    fixed = {m: z for m, z in profile.fixed_zones.items() if m in cyan}
    free = [z for z in profile.machine_zones(CYAN) if z not in fixed.values()]
    loose = [m for m in cyan if m not in fixed]
    if len(free) < len(loose):
        raise ValueError(f"{profile.name}: {len(loose)} machines for {len(free)} free zones")
    zones = dict(fixed)
    zones.update(zip(loose, rng.sample(free, len(loose))))
    step = profile.rotation_step_deg
    out: dict[str, tuple[int, int]] = {}
    for m in cyan:
        rot = rng.randrange(0, 360, step)
        out[m] = (zones[m], rot)
        out[mirror_machine_name(m)] = profile.mirror_placement(m, zones[m], rot)
    for kind in ("RS", "CS"):
        names = [m for m in cyan if machine_type(m) == kind]
        if names:
            c = rng.choice(sorted(names))
            mname = mirror_machine_name(c)
            out[c], out[mname] = out[mname], out[c]
    return out


def generate_layout(profile, rng: random.Random) -> dict[str, StationPose]:
    """machine -> :class:`StationPose` at its zone centre."""
    out = {}
    for m, (zone, rot) in generate_zones(profile, rng).items():
        x, y = profile.zone_centre(zone)
        out[m] = StationPose(m, zone, rot, x, y)
    return out


def swapped_machines(profile, layout) -> list[str]:
    """Machines standing in the other team's half (the swapped RS/CS pairs)."""
    return sorted(m for m, p in layout.items()
                  if profile.zone_team(p.zone) != (CYAN if m.startswith("C-") else MAGENTA))
