"""The 2017+ exploration (refbox HEAD): zone and rotation reports inside PRODUCTION.

There is no EXPLORATION phase: the first ``exploration_time`` game seconds
of PRODUCTION (180 s) are the exploration window.  A MachineReport entry
names one of the reporting team's machines and gives its zone and its
rotation (degrees), as the refbox's exploration.clp judges them:

- per team and machine only the first zone counts: right +1, wrong -1;
- the rotation counts only once the zone is right (a rotation sent before
  that is not recorded, one sent after a wrong zone is ignored), and only
  the first: equal to the machine's rotation +1, else -1; zone and rotation
  in one entry are judged together;
- a machine is *correctly reported* once zone and rotation are right; a
  wrong zone marks it as wrongly reported (a wrong rotation leaves it
  undecided, as in the refbox);
- an entry without a name but with a type ("BS", "RS", ...) and a zone is a
  type report (marker-less robots): per team and (type, zone) only the first
  counts, and a team may not report more machines of a type than it has.
  If a machine of that type stands in that zone (of either team) its name
  is revealed in MachineReportInfo's ``reported_types``; a wrong one costs
  ``type_feedback_wrong`` (-1);
- entries for the other team's machines or unknown names are ignored.

After the window the refbox releases the ground truth: every machine counts
as correctly reported and MachineInfo carries zone and rotation for all;
before, only correctly reported machines carry them.

Signal towers during the window (machine-lights.clp): yellow until the zone
is reported, yellow blinking once the zone is right, red + yellow after a
wrong zone, red + yellow blinking after a wrong rotation; a correctly
reported machine shows its production state's lights.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from rll_bt.rules import CYAN, MAGENTA, machine_team, machine_type

from .exploration2016 import STATE_NAMES as _STATE
from .exploration2016 import ok_word, zone_label
from .world import BLINK, ON, lights

UNREPORTED = lights(yellow=ON)
ZONE_RIGHT = lights(yellow=BLINK)
ZONE_WRONG = lights(red=ON, yellow=ON)
ROTATION_WRONG = lights(red=ON, yellow=BLINK)


@dataclass
class NameReport:
    """What a team reported for one of its machines; the first value of each field counts."""

    zone: int | None = None
    zone_ok: bool | None = None
    rotation: int | None = None
    rotation_ok: bool | None = None

    @property
    def fully_correct(self) -> bool:
        return bool(self.zone_ok and self.rotation_ok)

    @property
    def correct(self) -> bool | None:
        """The refbox's ``correctly-reported``: True, False (wrong zone) or None (open)."""
        if self.fully_correct:
            return True
        return False if self.zone_ok is False else None


@dataclass(frozen=True)
class TypeReport:
    """A report without a name: ``type`` in ``zone``; ``machine`` is the machine found
    there (None when the report was wrong)."""

    type: str
    zone: int
    machine: str | None

    @property
    def ok(self) -> bool:
        return self.machine is not None


@dataclass(frozen=True)
class Judgement2025:
    """The outcome of one entry: awards as (points, reason), a text and event data."""

    machine: str | None
    awards: tuple[tuple[int, str], ...]
    text: str
    data: dict = field(default_factory=dict)


class Exploration2025:
    """Report state of one game.  ``placements``: machine -> (zone, rotation in degrees)."""

    def __init__(self, profile, placements: dict[str, tuple[int, int]]):
        self.profile = profile
        self.placements = dict(placements)
        self.reports: dict[str, dict[str, NameReport]] = {CYAN: {}, MAGENTA: {}}
        self.type_reports: dict[str, list[TypeReport]] = {CYAN: [], MAGENTA: []}
        self.released = False

    # -- reports ---------------------------------------------------------------
    def judge(self, team: str, entry) -> Judgement2025 | None:
        """Score one entry of ``team``'s MachineReport; None when it changes nothing."""
        if self.released:
            return None
        if entry.name:
            return self._judge_name(team, entry)
        if entry.type and entry.zone is not None:
            return self._judge_type(team, entry.type.upper(), int(entry.zone))
        return None

    def _judge_name(self, team: str, entry) -> Judgement2025 | None:
        name = entry.name
        if name not in self.placements or machine_team(name) != team:
            return None
        true_zone, true_rot = self.placements[name]
        rep = self.reports[team].setdefault(name, NameReport())
        s = self.profile.scoring
        awards: list[tuple[int, str]] = []
        if rep.zone is None and entry.zone is not None:
            rep.zone, rep.zone_ok = int(entry.zone), int(entry.zone) == true_zone
            zn = self._zone_name(rep.zone)
            awards.append((s.explore_zone_ok, f"correct zone {zn} for {name}") if rep.zone_ok
                          else (s.explore_zone_wrong, f"wrong zone {zn} for {name}"))
        if rep.rotation is None and entry.rotation is not None and rep.zone_ok is not None:
            rep.rotation = int(entry.rotation)
            if rep.zone_ok:
                rep.rotation_ok = rep.rotation == true_rot
                awards.append((s.explore_rotation_ok, f"correct rotation {rep.rotation} for "
                               f"{name}") if rep.rotation_ok else
                              (s.explore_rotation_wrong, f"wrong rotation {rep.rotation} for {name}"))
        text = (f"{team} reported {name}: zone {ok_word(rep.zone_ok)}, "
                f"rotation {ok_word(rep.rotation_ok)}")
        return Judgement2025(name, tuple(awards), text,
                             {"zone_ok": rep.zone_ok, "rotation_ok": rep.rotation_ok,
                              "correct": rep.correct})

    def _judge_type(self, team: str, mtype: str, zone: int) -> Judgement2025 | None:
        mine = self.type_reports[team]
        if any(r.type == mtype and r.zone == zone for r in mine):
            return None
        have = sum(1 for m in self.profile.machines(team) if machine_type(m) == mtype)
        if sum(1 for r in mine if r.type == mtype) >= have:
            return None
        found = next((m for m, (z, _r) in sorted(self.placements.items())
                      if z == zone and machine_type(m) == mtype), None)
        mine.append(TypeReport(mtype, zone, found))
        zn = self._zone_name(zone)
        if found:
            return Judgement2025(None, (), f"{team} reported a {mtype} in {zn}: it is {found}",
                                 {"type_ok": True, "type": mtype, "zone": zone, "name": found})
        pts = self.profile.scoring.type_feedback_wrong
        return Judgement2025(None, ((pts, f"wrong type report {mtype} in {zn}"),) if pts else (),
                             f"{team} reported a {mtype} in {zn}: wrong",
                             {"type_ok": False, "type": mtype, "zone": zone})

    def release(self) -> None:
        """The exploration time is over: every machine counts as correctly reported."""
        self.released = True

    # -- reads -------------------------------------------------------------------
    def state(self, team: str, machine: str) -> NameReport | None:
        return self.reports[team].get(machine)

    def correctly_reported(self, team: str, machine: str) -> bool:
        """Whether ``team`` may use ``machine`` (its report is right, or the truth is out)."""
        if machine not in self.placements or machine_team(machine) != team:
            return False
        rep = self.reports[team].get(machine)
        return self.released or (rep is not None and rep.fully_correct)

    def reported(self, team: str) -> list[str]:
        """Machines ``team`` reported by name, in report order (MachineReportInfo)."""
        return list(self.reports[team])

    def type_feedback(self, team: str) -> list[TypeReport]:
        return list(self.type_reports[team])

    def report_lights(self, machine: str) -> dict[str, str] | None:
        """The tower of a machine not yet correctly reported; None once it shows its state."""
        team = machine_team(machine)
        if self.correctly_reported(team, machine):
            return None
        rep = self.reports[team].get(machine)
        if rep is None or rep.zone_ok is None:
            return UNREPORTED
        if rep.zone_ok is False:
            return ZONE_WRONG
        return ROTATION_WRONG if rep.rotation_ok is False else ZONE_RIGHT

    def report_fields(self, team: str, machine: str) -> dict:
        """MachineInfo fields about ``machine``'s exploration (field name -> value; enum
        values by name): zone and rotation only once it is correctly reported."""
        out: dict = {}
        if self.correctly_reported(team, machine):
            zone, rot = self.placements[machine]
            out.update(zone=zone, rotation=rot, correctly_reported=True,
                       exploration_zone_state=_STATE[True], exploration_rotation_state=_STATE[True])
            return out
        rep = self.reports[team].get(machine)
        if rep is not None:
            out.update(correctly_reported=False, exploration_zone_state=_STATE[rep.zone_ok],
                       exploration_rotation_state=_STATE[rep.rotation_ok])
        return out

    def _zone_name(self, zone: int) -> str:
        return zone_label(self.profile, zone)

