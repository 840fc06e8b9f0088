"""A rules profile: everything that differs between rule sets, as data and
pure functions.  Nothing outside ``rll_bt.rules`` and the message sets
hard-codes a rule set."""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from .geometry import MPS, ROBOT, WORKPIECE, MpsGeometry, RobotGeometry, WorkpieceGeometry
from .machines import MPS_TIMES, MachineTimes
from .zones import CYAN, MAGENTA, Rect

TEAMS = (CYAN, MAGENTA)
PREFIX = {CYAN: "C", MAGENTA: "M"}
RING_COLORS = ("RING_BLUE", "RING_GREEN", "RING_ORANGE", "RING_YELLOW")
BASE_COLORS = ("BASE_RED", "BASE_BLACK", "BASE_SILVER")
CAP_COLORS = ("CAP_BLACK", "CAP_GREY")
LIGHTS = ("RED", "YELLOW", "GREEN")


def other_team(team: str) -> str:
    return MAGENTA if team == CYAN else CYAN


def machine_team(name: str) -> str:
    if name.startswith("C-"):
        return CYAN
    if name.startswith("M-"):
        return MAGENTA
    raise ValueError(f"not a machine name: {name!r} (expected C-XX or M-XX)")


def machine_type(name: str) -> str:
    """'C-RS1' -> 'RS'."""
    machine_team(name)
    return name[2:4]


def mirror_machine_name(name: str) -> str:
    return ("M-" if machine_team(name) == CYAN else "C-") + name[2:]


@dataclass(frozen=True)
class Phases:
    setup: float
    exploration: float          # length of the EXPLORATION phase (0 when the rules have none)
    production: float
    overtime: float
    exploration_in_production: float = 0.0   # 2022+: first seconds of PRODUCTION explore

    @property
    def exploration_deadline(self) -> float:
        """Seconds of exploration, whichever phase holds it."""
        return self.exploration or self.exploration_in_production


@dataclass(frozen=True)
class Scoring:
    # exploration
    explore_type_ok: int = 0
    explore_type_wrong: int = 0
    explore_zone_ok: int = 0
    explore_zone_wrong: int = 0
    explore_rotation_ok: int = 0
    explore_rotation_wrong: int = 0
    type_feedback_wrong: int = 0          # 2025: a report without name whose type/zone is wrong
    # production
    additional_base: int = 2
    ring_by_cost: tuple[int, int, int] = (5, 10, 20)       # ring step of colour cost 0/1/2
    precap_by_complexity: tuple[int, int, int, int] = (0, 10, 30, 80)
    cap_mounted: int = 10
    cap_retrieved: int = 0
    delivery_by_complexity: tuple[int, int, int, int] = (20, 20, 20, 20)
    delivery_late_grace: float = 10.0     # seconds after the window end with reduced points
    delivery_late_penalty: float = 1.5   # points per full second late, inside the grace period
    delivery_too_late: int = 5
    # 2025 (orders.clp): late by up to 1/steps, 2/steps, ... of the window's length costs
    # 1/steps, 2/steps, ... of late_share of the delivery points (0 steps: the 2016 scheme)
    delivery_late_steps: int = 0
    delivery_late_share: float = 0.0
    delivery_wrong: int = 1
    competitive_first: int = 0
    competitive_second: int = 0
    # storage station (2025): each store, retrieve and relocation
    ss_store: int = 0
    ss_retrieve: int = 0
    ss_relocate: int = 0
    # 2025: a machine going BROKEN takes back +additional_base per unused base on an RS
    # slide and +cap_retrieved for a retrieved cap still in a CS
    break_revokes: bool = False


@dataclass(frozen=True)
class OrderShape:
    """One slot of the order schedule: its complexity (or choices) and kind."""
    complexities: tuple[int, ...]
    quantity: int = 1
    standing: bool = False      # active for the whole production phase
    overtime: bool = False      # only during overtime
    competitive: bool = False


@dataclass(frozen=True)
class Profile:
    name: str
    year: int
    zones: object                          # ZoneLayout2016 | ZoneLayout2025
    machine_types: tuple[str, ...]         # per team, e.g. ("BS", "DS", "RS1", ...)
    fixed_zones: dict[str, int]            # machine name -> zone, e.g. C-BS -> 9
    tags: dict[str, tuple[int, int]]       # machine name -> (input tag, output tag)
    tag_family: str                        # "alvar" or "aruco" (the rulebook's)
    tag_size: float                        # printed marker width, metres
    phases: Phases
    scoring: Scoring
    orders: tuple[OrderShape, ...]
    light_codes: dict[int, tuple[str, ...]] = field(default_factory=dict)   # 2016 exploration
    rs_colors: dict[str, tuple[str, str]] | None = None   # fixed RS colours (2025); None: random
    exploration_reports: str = "type+zone"   # 2016: name, type, zone; 2025: name, zone, rotation
    rotation_step_deg: int = 45
    insertion: dict[str, Rect] = field(default_factory=dict)
    excluded_machine_zones: frozenset[int] = frozenset()
    down_period: tuple[float, float] = (30.0, 120.0)
    prepare_requires_report: bool = False   # 2025: PrepareMachine rejected until correctly reported
    # production rules of the refbox (refbox-rules.md)
    unprepared_input_breaks: bool = False   # 2016: a workpiece put on a machine not PREPARED breaks it
    stuck_timeout: float | None = None      # 2025: PREPARED/PROCESSING/PROCESSED this long -> BROKEN
    rs_paid_at_prepare: bool = False        # 2025: an RS prepared without its bases breaks at once
    wait_idle_after_delivery: bool = False  # 2025: WAIT-IDLE after a delivery or a store
    down_start: float = 1.0                 # earliest start of a down period (production s)
    # 2025: products in every storage station at the start: (shelf, slot, base, cap)
    prestored: tuple[tuple[int, int, str, str], ...] = ()
    # what a human referee penalises (rulebook), reported as referee events
    referee_penalties: dict[str, int] = field(default_factory=dict)
    machine_times: MachineTimes = MPS_TIMES
    mps: MpsGeometry = MPS
    robot: RobotGeometry = ROBOT
    workpiece: WorkpieceGeometry = WORKPIECE

    # -- machines ---------------------------------------------------------
    def machines(self, team: str | None = None) -> list[str]:
        teams = TEAMS if team is None else (team,)
        return [f"{PREFIX[t]}-{m}" for t in teams for m in self.machine_types]

    def tag_ids(self, machine: str) -> tuple[int, int]:
        """(input tag id, output tag id)."""
        try:
            return self.tags[machine]
        except KeyError:
            raise ValueError(f"{self.name} has no machine {machine!r}") from None

    def machine_for_tag(self, tag_id: int) -> tuple[str, str] | None:
        """(machine name, "INPUT"|"OUTPUT") for a tag id, None when unknown."""
        return self._tag_index.get(tag_id)

    @property
    def all_tag_ids(self) -> frozenset[int]:
        return frozenset(self._tag_index)

    @property
    def _tag_index(self) -> dict[int, tuple[str, str]]:
        idx = self.__dict__.get("_tag_index_cache")
        if idx is None:
            idx = {}
            for m, (i, o) in self.tags.items():
                idx[i] = (m, "INPUT")
                idx[o] = (m, "OUTPUT")
            object.__setattr__(self, "_tag_index_cache", idx)
        return idx

    # -- zones ------------------------------------------------------------
    @property
    def field(self) -> Rect:
        return self.zones.field

    def zone_at(self, x: float, y: float) -> int | None:
        return self.zones.zone_at(x, y)

    def zone_centre(self, zone: int) -> tuple[float, float]:
        return self.zones.centre(zone)

    def zone_name(self, zone: int) -> str:
        return self.zones.name(zone)

    def zone_number(self, name: str) -> int:
        return self.zones.number(name)

    def zone_team(self, zone: int) -> str:
        return self.zones.team(zone)

    def mirror_zone(self, zone: int) -> int:
        return self.zones.mirror(zone)

    def team_zones(self, team: str) -> list[int]:
        return [z for z in self.zones.all_zones if self.zones.team(z) == team]

    def machine_zones(self, team: str) -> list[int]:
        """Zones of ``team``'s half where a machine may stand."""
        return [z for z in self.team_zones(team) if z not in self.excluded_machine_zones]

    def mirror_point(self, x: float, y: float) -> tuple[float, float]:
        return (-x, y)

    # -- orientation ------------------------------------------------------
    def discretise_rotation(self, deg: float) -> int:
        step = self.rotation_step_deg
        return int(round((deg % 360.0) / step)) * step % 360

    def mirror_rotation(self, deg: int) -> int:
        """Cyan -> magenta rotation of a mirrored machine: 0->180, 45->135,
        90->90, 135->45, 180->0, 225->315, 270->270, 315->225."""
        return int((180 - deg) % 360)

    def mirror_placement(self, machine: str, zone: int, rotation: int) -> tuple[int, int]:
        """Zone and rotation of the magenta twin of a cyan machine.

        Rotation mirrors as :meth:`mirror_rotation`.  From 2017 on, a cyan RS
        or CS next to a wall (y = 8, y = 1, x = 7, or the insertion-adjacent
        row y = 2 with x = 5..7) gives its twin a fixed rotation that keeps the
        shelf/slide off the wall: y = 8 -> 180, y in {1, 2} -> 0, x = 7 -> 270.
        """
        if machine_team(machine) != CYAN:
            raise ValueError(f"mirror_placement takes a cyan machine, not {machine!r}")
        wall = self._wall_rotation(machine, zone)
        return self.zones.mirror(zone), self.mirror_rotation(rotation) if wall is None else wall

    def _wall_rotation(self, machine: str, cyan_zone: int) -> int | None:
        """The fixed rotation a magenta RS or CS gets from 2017 on when its cyan twin
        stands in ``cyan_zone`` by a wall (see :meth:`mirror_placement`); None when the
        twin's rotation mirrors."""
        if self.year < 2017 or machine_type(machine) not in ("RS", "CS"):
            return None
        x, y = self.zones.digits(cyan_zone)
        if y == 8:
            return 180
        if y == 1 or (y == 2 and 5 <= x <= 7):
            return 0
        if x == 7:
            return 270
        return None

    def twin_mirrors(self, machine: str, zone: int) -> bool:
        """Whether ``machine`` (standing in ``zone``) and its twin stand as mirror images,
        rotation included; False for a 2017+ RS or CS pair by a wall, whose magenta
        machine gets a fixed rotation instead."""
        cyan_zone = zone if machine_team(machine) == CYAN else self.zones.mirror(zone)
        return self._wall_rotation(machine, cyan_zone) is None

    # -- lights -----------------------------------------------------------
    def light_code(self, code: int) -> tuple[str, ...]:
        """Lights on for a 2016 exploration light code (1 = G ... 7 = R+Y+G)."""
        try:
            return self.light_codes[code]
        except KeyError:
            raise ValueError(f"{self.name}: no light code {code}") from None

    # -- scoring ----------------------------------------------------------
    def delivery_points(self, complexity: int, delivered_at: float, window_end: float,
                        window_start: float | None = None) -> int:
        """Delivery points (without the product's steps) for an order of ``complexity``
        delivered at ``delivered_at`` whose window is [``window_start``, ``window_end``].

        2016: in the window full, up to ``delivery_late_grace`` late
        int(points - 1.5 * floor(seconds late)), later ``delivery_too_late``.
        2025 (``delivery_late_steps``): the refbox's orders.clp deducts
        int(p * late_share * points), p growing by 1/steps while the delay exceeds
        p times the window's length, at most 1 (75 % with the defaults)."""
        s = self.scoring
        full = s.delivery_by_complexity[complexity]
        if delivered_at <= window_end:
            return full
        late = delivered_at - window_end
        if s.delivery_late_steps > 0:
            length = window_end - (window_end if window_start is None else window_start)
            share = 0.0
            while share < 1.0 and late > share * length:
                share += 1.0 / s.delivery_late_steps
            return full - int(min(share, 1.0) * s.delivery_late_share * full)
        if late <= s.delivery_late_grace:
            # the refbox's orders.clp: int(points - 1.5 * floor(seconds late))
            return max(int(full - s.delivery_late_penalty * math.floor(late)), 0)
        return s.delivery_too_late

    def ring_points(self, cost: int) -> int:
        return self.scoring.ring_by_cost[cost]

    # -- randomised game set-up (pure functions of a random generator) ------
    def ring_setup(self, rng: random.Random) -> tuple[dict[str, tuple[str, str]], dict[str, int]]:
        """(RS colours per station type, additional bases per ring colour).

        Per game one colour costs 2 bases, one costs 1 and two cost 0.  With
        random RS colours (2016) RS1 gets colours 1-2 of a random permutation
        and RS2 colours 3-4, each RS with one free and one costly colour; with
        fixed colours (2025) only the costs are random.
        """
        if self.rs_colors is None:
            perm = list(RING_COLORS)
            rng.shuffle(perm)
            rs = {"RS1": (perm[0], perm[1]), "RS2": (perm[2], perm[3])}
            expensive_rs = rng.choice(("RS1", "RS2"))
            costs = {}
            for name, (c1, c2) in rs.items():
                costly = c1 if rng.random() < 0.5 else c2
                costs[costly] = 2 if name == expensive_rs else 1
                costs[c2 if costly == c1 else c1] = 0
        else:
            rs = dict(self.rs_colors)
            perm = list(RING_COLORS)
            rng.shuffle(perm)
            costs = {perm[0]: 2, perm[1]: 1, perm[2]: 0, perm[3]: 0}
        return rs, costs


def rotation_to_theta(deg: float) -> float:
    return math.radians(deg)


def theta_to_rotation(theta: float) -> float:
    return math.degrees(theta) % 360.0
