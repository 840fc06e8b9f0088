"""Seeded field layouts: where every station of both teams stands.

Pure functions of a rules profile and a seed (or a ``random.Random``), used
by the world and by the simulated referee box alike::

    layout = generate_layout(rules.profile("rcll2016"), seed=7)
    layout.pose("C-RS1")       # Pose2D in the field frame (theta = rotation)
    layout.zone("C-RS1")       # zone number of the profile
    layout.rotation("C-RS1")   # degrees, a multiple of 45

2016 (:func:`placement_2016`, as the 2016 refbox): C-BS in Z9 and C-DS in Z4,
the other cyan stations in distinct random cyan zones, each at a random
position inside its zone (footprint inside with a margin) and a random
rotation in 45 degree steps; magenta mirrors cyan (zone n -> n + 12, x -> -x,
rotation by ``profile.mirror_placement``); then one RS and one CS (random
index) swap their places between the teams.

2017+ (:func:`placement_2025`): the cyan stations as the real refbox's
solver places them (:mod:`.placing2025`: the zones in front of every
input and output kept free, the border, centre line and insertion zones
free, neighbouring zones and column 1 allowed), at zone centres with 45
degree rotations; the magenta twin by ``profile.mirror_placement`` (with its
wall rule), then the RS/CS swap of zone and rotation.

2016 layouts also keep every station reachable by our own check: the points
0.45 m in front of its input and output faces lie inside the field, clear of
the walls and of other stations, and the lanes from the insertion areas into
the field stay free.
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from rll_bt import rules
from rll_bt.backend import Pose2D
from rll_bt.rules import CYAN, MAGENTA, Profile, machine_type, mirror_machine_name

from . import placing2025
from .collide import Box2D, box_distance
from .fieldgeom import approach_points, entry_point, footprint

ZONE_MARGIN_2016 = 0.1     # footprint to zone edge, metres
MIN_STATION_GAP = 0.6      # between two footprints, so a robot fits through
MIN_APPROACH_CLEARANCE = 0.3
MAX_TRIES = 500


class LayoutError(RuntimeError):
    """No layout satisfying the constraints was found."""


@dataclass(frozen=True)
class MachinePlacement:
    machine: str
    zone: int
    rotation_deg: int
    pose: Pose2D               # field frame; pose.theta == radians(rotation_deg)


@dataclass(frozen=True)
class FieldLayout:
    """Placements of both teams' stations.  ``swapped`` lists the machine
    types (e.g. ``("RS2", "CS1")``) whose cyan and magenta stations traded
    places."""
    profile: str
    machines: dict[str, MachinePlacement] = field(hash=False)
    seed: int | None = None
    swapped: tuple[str, ...] = ()

    def __getitem__(self, machine: str) -> MachinePlacement:
        try:
            return self.machines[machine]
        except KeyError:
            raise KeyError(f"no machine {machine!r} in the layout "
                           f"(known: {', '.join(sorted(self.machines))})") from None

    def __iter__(self):
        return iter(sorted(self.machines))

    def __len__(self) -> int:
        return len(self.machines)

    def pose(self, machine: str) -> Pose2D:
        return self[machine].pose

    def zone(self, machine: str) -> int:
        return self[machine].zone

    def rotation(self, machine: str) -> int:
        return self[machine].rotation_deg

    def machine_in_zone(self, zone: int) -> str | None:
        for m, pl in self.machines.items():
            if pl.zone == zone:
                return m
        return None

    def to_dict(self) -> dict:
        return {"profile": self.profile, "seed": self.seed, "swapped": list(self.swapped),
                "machines": {m: {"zone": pl.zone, "rotation": pl.rotation_deg,
                                 "x": pl.pose.x, "y": pl.pose.y}
                             for m, pl in sorted(self.machines.items())}}

    @classmethod
    def from_dict(cls, data: dict) -> FieldLayout:
        machines = {}
        for m, d in data["machines"].items():
            rot = int(d["rotation"])
            machines[m] = MachinePlacement(m, int(d["zone"]), rot,
                                           Pose2D(float(d["x"]), float(d["y"]), math.radians(rot)))
        return cls(data["profile"], machines, data.get("seed"), tuple(data.get("swapped", ())))


def _placement(machine: str, zone: int, rotation: int, x: float, y: float) -> MachinePlacement:
    rotation = int(rotation) % 360
    return MachinePlacement(machine, zone, rotation,
                            Pose2D(round(x, 3), round(y, 3), math.radians(rotation)))


def _twin(profile: Profile, pl: MachinePlacement, keep_xy: bool) -> MachinePlacement:
    """The magenta twin of a cyan placement."""
    zone, rot = profile.mirror_placement(pl.machine, pl.zone, pl.rotation_deg)
    if keep_xy:
        x, y = profile.mirror_point(pl.pose.x, pl.pose.y)
    else:
        x, y = profile.zone_centre(zone)
    return _placement(mirror_machine_name(pl.machine), zone, rot, x, y)


def _reachable(profile: Profile, new: list[MachinePlacement], placed: list[MachinePlacement]) -> bool:
    """Footprints apart, faces approachable, insertion lanes free."""
    f = profile.field
    margin = profile.robot.radius + 0.05
    boxes = {pl.machine: footprint(profile, pl.pose) for pl in placed + new}
    for pl in new:
        box = boxes[pl.machine]
        for other, ob in boxes.items():
            if other != pl.machine and box_distance(box, ob) < MIN_STATION_GAP:
                return False
        for x, y in approach_points(profile, pl.pose).values():
            if not (f.x_min + margin <= x <= f.x_max - margin and f.y_min + margin <= y <= f.y_max - margin):
                return False
            for other, ob in boxes.items():
                if other != pl.machine and ob.sdf(x, y) < MIN_APPROACH_CLEARANCE:
                    return False
        for team in (CYAN, MAGENTA):
            for n in (1, 2, 3):
                ex, ey = entry_point(profile, team, n)
                if box.sdf(ex, ey) < profile.robot.radius + 0.15:
                    return False
    return True


def _swap(profile: Profile, machines: dict[str, MachinePlacement], rng: random.Random) -> tuple[str, ...]:
    """One RS and one CS (random index) trade places between the teams."""
    swapped = []
    for kind in ("RS", "CS"):
        choices = [t for t in profile.machine_types if machine_type("C-" + t) == kind]
        if not choices:
            continue
        t = rng.choice(choices)
        c, m = machines[f"C-{t}"], machines[f"M-{t}"]
        machines[c.machine] = MachinePlacement(c.machine, m.zone, m.rotation_deg, m.pose)
        machines[m.machine] = MachinePlacement(m.machine, c.zone, c.rotation_deg, c.pose)
        swapped.append(t)
    return tuple(swapped)


def _random_rotation(profile: Profile, rng: random.Random) -> int:
    step = profile.rotation_step_deg
    return rng.randrange(0, 360, step)


def _pose_in_zone_2016(profile: Profile, zone: int, rotation: int, rng: random.Random,
                       margin: float) -> tuple[float, float]:
    b = profile.zones.bounds(zone)
    ex, ey = Box2D(0.0, 0.0, math.radians(rotation),
                   profile.mps.depth / 2.0, profile.mps.width / 2.0).half_extents_world()
    x = rng.uniform(b.x_min + ex + margin, b.x_max - ex - margin)
    y = rng.uniform(b.y_min + ey + margin, b.y_max - ey - margin)
    return x, y


def placement_2016(profile: Profile, rng: random.Random, *, margin: float = ZONE_MARGIN_2016,
                   seed: int | None = None) -> FieldLayout:
    """The 2016 placement (see the module docstring)."""
    cyan = profile.machines(CYAN)
    fixed = {m: z for m, z in profile.fixed_zones.items() if m in cyan}
    for m, z in profile.fixed_zones.items():
        if m not in cyan and profile.mirror_zone(fixed[mirror_machine_name(m)]) != z:
            raise LayoutError(f"{profile.name}: fixed zone of {m} is not the mirror of its twin's")
    free = [z for z in profile.machine_zones(CYAN) if z not in fixed.values()]
    loose = [m for m in cyan if m not in fixed]
    zones: dict[str, int] = {}

    def begin() -> None:              # each try draws the zones first, then the poses
        zones.clear()
        zones.update(fixed)
        zones.update(zip(loose, rng.sample(free, len(loose))))

    def draw(machine: str, placed: list[MachinePlacement]) -> MachinePlacement:
        rot = _random_rotation(profile, rng)
        x, y = _pose_in_zone_2016(profile, zones[machine], rot, rng, margin)
        return _placement(machine, zones[machine], rot, x, y)

    return _generate(profile, rng, seed, draw, keep_xy=True, tries=50, begin=begin)


def _generate(profile: Profile, rng: random.Random, seed: int | None, draw, keep_xy: bool,
              tries: int, begin=None) -> FieldLayout:
    """Place the cyan stations one by one with ``draw(machine, placed)`` (a
    candidate, or None to give the layout up; at most ``tries`` per station),
    each with its magenta twin, keeping everything reachable; then swap.
    Starts over (calling ``begin()`` first) when stuck."""
    for _ in range(MAX_TRIES):
        if begin:
            begin()
        placed: list[MachinePlacement] = []
        if all(_place_pair(profile, m, placed, draw, keep_xy, tries) for m in profile.machines(CYAN)):
            machines = {pl.machine: pl for pl in placed}
            return FieldLayout(profile.name, machines, seed, _swap(profile, machines, rng))
    raise LayoutError(f"{profile.name}: no reachable layout found in {MAX_TRIES} tries")


def _place_pair(profile: Profile, machine: str, placed: list[MachinePlacement], draw, keep_xy: bool,
                tries: int) -> bool:
    for _ in range(tries):
        pl = draw(machine, placed)
        if pl is None:
            return False
        pair = [pl, _twin(profile, pl, keep_xy)]
        if _reachable(profile, pair, placed):
            placed += pair
            return True
    return False


def placement_2025(profile: Profile, rng: random.Random, *, seed: int | None = None) -> FieldLayout:
    """A random 2017+ placement with the real refbox's constraints (:mod:`.placing2025`):
    the cyan machines at zone centres, each magenta twin by ``profile.mirror_placement``
    (with its wall rule), then the RS/CS swap of zone and rotation."""
    cyan = placing2025.solve(rng)
    placed: list[MachinePlacement] = []
    for machine in profile.machines(CYAN):
        x, y, angle = cyan[machine[2:]]
        zone = 10 * x + y
        cx, cy = profile.zone_centre(zone)
        pl = _placement(machine, zone, angle, cx, cy)
        placed += [pl, _twin(profile, pl, keep_xy=False)]
    machines = {pl.machine: pl for pl in placed}
    return FieldLayout(profile.name, machines, seed, _swap(profile, machines, rng))


def generate_layout(profile: Profile | str | None = None, seed: int = 0) -> FieldLayout:
    """The layout for ``profile`` (name or object; default rcll2016) and ``seed``."""
    prof = profile if isinstance(profile, Profile) else rules.profile(profile)
    rng = random.Random(seed)
    if prof.year < 2017:
        return placement_2016(prof, rng, seed=seed)
    return placement_2025(prof, rng, seed=seed)
