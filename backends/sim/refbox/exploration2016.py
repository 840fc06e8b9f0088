"""The 2016 exploration: light codes, type strings and MachineReport scoring.

Per game each machine pair (C-X and its twin M-X) gets a distinct light code
of the profile (1 = G ... 7 = R+Y+G, all steady), and each code a random
8-character *type string*.  ExplorationInfo (public, 1 Hz) lists, per code,
its type string and its three LightSpecs, in a fresh random order each time,
and the 12 zones of each team with the swapped RS/CS zones exchanged.

A MachineReport entry names a machine and gives the type string read off its
lights and its zone.  Per team and machine only the first type and the first
zone count: type right +5 / wrong -4, zone right +3 / wrong -2 (profile
scoring).  An entry for a machine of the other team is ignored and costs
nothing: the 2016 refbox defines ``EXPLORATION-INVALID-REPORT-POINTS`` (-6)
in globals.clp, but only rules that are commented out use it
(refbox-rules.md); unknown names are ignored too.  A fully correct report
(type and zone right) makes the machine blink green for ``feedback_time``
game seconds, a wrong one blink red.
"""
from __future__ import annotations

import random
import string
from dataclasses import dataclass, field

from rll_bt.rules import CYAN, MAGENTA, machine_team

from .world import BLINK, OFF, ON, lights

STATE_NAMES = {None: "NO_REPORT", True: "CORRECT_REPORT", False: "WRONG_REPORT"}
TYPE_STRING_CHARS = string.ascii_uppercase + string.digits
TYPE_STRING_LEN = 8


@dataclass(frozen=True)
class ReportEntry:
    """One MachineReportEntry: machine ``name``, the ``type`` string, the ``zone`` number
    (and ``rotation``); None for a field the report left out."""

    name: str | None
    type: str | None = None
    zone: int | None = None
    rotation: int | None = None      # degrees (2017+ reports; unused by the 2016 rules)


@dataclass
class MachineReports:
    """What ``team`` reported for one machine; the first value of each field counts."""

    type: str | None = None
    zone: int | None = None
    type_ok: bool | None = None
    zone_ok: bool | None = None

    @property
    def fully_correct(self) -> bool:
        return bool(self.type_ok and self.zone_ok)

    @property
    def wrong(self) -> bool:
        return self.type_ok is False or self.zone_ok is False


@dataclass(frozen=True)
class Judgement:
    """The outcome of one report entry: awards as (points, reason) and the light
    feedback to show ("correct", "wrong" or None)."""

    machine: str
    awards: tuple[tuple[int, str], ...] = ()
    feedback: str | None = None
    type_ok: bool | None = None
    zone_ok: bool | None = None
    team: str = ""

    @property
    def text(self) -> str:
        return (f"{self.team} reported {self.machine}: type {ok_word(self.type_ok)}, "
                f"zone {ok_word(self.zone_ok)}")

    @property
    def data(self) -> dict:
        return {"type_ok": self.type_ok, "zone_ok": self.zone_ok, "feedback": self.feedback}


@dataclass
class Exploration2016:
    """Light codes, type strings and report state of one game."""

    profile: object
    zones: dict[str, int]                      # machine -> zone
    rng: random.Random
    feedback_time: float = 5.0
    code_of_pair: dict[str, int] = field(default_factory=dict)     # "RS1" -> code
    type_of_code: dict[int, str] = field(default_factory=dict)     # code -> type string
    reports: dict[str, dict[str, MachineReports]] = field(default_factory=dict)

    def __post_init__(self):
        pairs = list(self.profile.machine_types)
        codes = sorted(self.profile.light_codes)
        if len(codes) < len(pairs):
            raise ValueError(f"{self.profile.name}: {len(codes)} light codes for "
                             f"{len(pairs)} machine pairs")
        chosen = self.rng.sample(codes, len(pairs))
        self.code_of_pair = dict(zip(pairs, chosen))
        used: set[str] = set()
        for code in sorted(chosen):
            while True:
                s = "".join(self.rng.choice(TYPE_STRING_CHARS) for _ in range(TYPE_STRING_LEN))
                if s not in used:
                    break
            used.add(s)
            self.type_of_code[code] = s
        self.reports = {CYAN: {}, MAGENTA: {}}

    # -- what robots see ---------------------------------------------------------
    def code_of(self, machine: str) -> int:
        return self.code_of_pair[machine[2:]]

    def expected_type(self, machine: str) -> str:
        """The type string a correct report of ``machine`` carries."""
        return self.type_of_code[self.code_of(machine)]

    def code_lights(self, code: int) -> dict[str, str]:
        on = set(self.profile.light_code(code))
        return lights(*(ON if c in on else OFF for c in ("RED", "YELLOW", "GREEN")))

    def machine_lights(self, machine: str) -> dict[str, str]:
        """The steady light code ``machine`` shows during exploration."""
        return self.code_lights(self.code_of(machine))

    @staticmethod
    def feedback_lights(feedback: str) -> dict[str, str]:
        return lights(green=BLINK) if feedback == "correct" else lights(red=BLINK)

    def signals(self, rng: random.Random) -> list[tuple[str, dict[str, str]]]:
        """(type string, lights) per code in use, shuffled with ``rng`` so the order
        gives nothing away."""
        out = [(self.type_of_code[c], self.code_lights(c))
               for c in sorted(self.code_of_pair.values())]
        rng.shuffle(out)
        return out

    def zone_lists(self) -> dict[str, list[int]]:
        """Each team's 12 exploration zones, with a swapped machine's zone exchanged
        for its twin's (the 2016 refbox's ExplorationInfo zones)."""
        z = self.profile.zones
        lists = {CYAN: [n for n in z.all_zones if z.team(n) == CYAN],
                 MAGENTA: [n for n in z.all_zones if z.team(n) == MAGENTA]}
        for m, zone in sorted(self.zones.items()):
            if machine_team(m) != CYAN or m[2:4] not in ("RS", "CS"):
                continue
            if z.team(zone) == MAGENTA:           # swapped into the other half
                i = lists[MAGENTA].index(zone)
                lists[CYAN][i], lists[MAGENTA][i] = lists[MAGENTA][i], lists[CYAN][i]
        return lists

    # -- reports ---------------------------------------------------------------
    def reported(self, team: str) -> list[str]:
        """Machines ``team`` has reported anything for, in report order."""
        return list(self.reports[team])

    def state(self, team: str, machine: str) -> MachineReports | None:
        return self.reports[team].get(machine)

    def correctly_reported(self, team: str, machine: str) -> bool:
        rep = self.reports[team].get(machine)
        return rep is not None and rep.fully_correct

    def report_fields(self, team: str, machine: str) -> dict:
        """MachineInfo fields about ``machine``'s report (field -> value, enums by name):
        the zone once reported right, the report states."""
        rep = self.reports[team].get(machine)
        if rep is None:
            return {"exploration_type_state": STATE_NAMES[None],
                    "exploration_zone_state": STATE_NAMES[None]}
        out = {"correctly_reported": rep.fully_correct,
               "exploration_type_state": STATE_NAMES[rep.type_ok],
               "exploration_zone_state": STATE_NAMES[rep.zone_ok]}
        if rep.zone_ok:
            out["zone"] = self.zones[machine]
        return out

    def judge(self, team: str, entry: ReportEntry) -> Judgement | None:
        """Score one entry of ``team``'s MachineReport; None when it changes nothing."""
        if entry.name not in self.zones:
            return None
        s = self.scoring
        known = self.reports[team].get(entry.name)
        if machine_team(entry.name) != team:
            return None             # the other team's machine: no rule matches it
        rep = known if known is not None else MachineReports()
        self.reports[team][entry.name] = rep
        awards: list[tuple[int, str]] = []
        if rep.type is None and entry.type:
            rep.type = entry.type
            rep.type_ok = entry.type == self.expected_type(entry.name)
            awards.append((s.explore_type_ok, f"correct type for {entry.name}") if rep.type_ok
                          else (s.explore_type_wrong, f"wrong type {entry.type!r} for {entry.name}"))
        if rep.zone is None and entry.zone:
            rep.zone = entry.zone
            rep.zone_ok = entry.zone == self.zones[entry.name]
            zn = self._zone_name(entry.zone)
            awards.append((s.explore_zone_ok, f"correct zone {zn} for {entry.name}") if rep.zone_ok
                          else (s.explore_zone_wrong, f"wrong zone {zn} for {entry.name}"))
        if not awards:
            return None
        feedback = "wrong" if rep.wrong else ("correct" if rep.fully_correct else None)
        return Judgement(entry.name, tuple(awards), feedback, rep.type_ok, rep.zone_ok, team)

    @property
    def scoring(self):
        return self.profile.scoring

    def _zone_name(self, zone: int) -> str:
        return zone_label(self.profile, zone)


def ok_word(v) -> str:
    """None/True/False as "-", "right", "wrong" (report texts)."""
    return "-" if v is None else ("right" if v else "wrong")


def zone_label(profile, zone: int) -> str:
    """``zone``'s name in ``profile`` ("Z4", "C_Z23"), or "zone N" for a number it lacks."""
    try:
        return profile.zone_name(zone)
    except ValueError:
        return f"zone {zone}"
