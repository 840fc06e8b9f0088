"""The symmetry sanity check: the most probable *consistent* machine set.

The refbox places the stations mirrored: if C-X stands in zone z then M-X
stands in mirror(z), with the same light code (2016) and the mirrored
rotation (2017+; a cyan-half RS/CS next to a wall gives its magenta-half twin
a fixed rotation instead).  Then one RS pair and one CS pair swap places, so
exactly one RS and one CS of each team stand in the other team's half; the
BS, DS (and SS) never do, and in 2016 the BS and DS have fixed zones.  No two
machines share a zone.

Each pair X = (C-X, M-X) is placed by the zone z of C-X.  Its score is
``log P_C(z) + log P_M(mirror z)`` from the fused zone beliefs (an
unobserved machine contributes its uniform share), plus an "unknown" option
holding the mass of every zone nobody observed.  A branch-and-bound search
picks the assignment of all pairs with the highest total score that meets the
constraints; each pair's confidence is its normalised pair posterior.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from rll_bt.rules import CYAN, MAGENTA, PREFIX, Profile

from ..knowledge import model as M
from ..knowledge.fusion import DiscreteBelief

_SWAPPING = ("RS", "CS")


@dataclass(frozen=True)
class MachineGuess:
    """A machine's place in the consistent set (None where unknown)."""

    name: str
    zone: int | None
    zone_confidence: float
    orientation: int | None = None
    orientation_confidence: float = 0.0
    light: tuple[str, ...] | None = None
    light_confidence: float = 0.0


@dataclass
class ConsistentSet:
    """Result of :func:`consistent_set`: guesses for every machine of both teams."""

    machines: dict[str, MachineGuess] = field(default_factory=dict)
    conflicts: list[str] = field(default_factory=list)   # best single belief was overruled
    score: float = 0.0

    def own(self, team: str) -> dict[str, MachineGuess]:
        p = PREFIX[team] + "-"
        return {n: g for n, g in self.machines.items() if n.startswith(p)}


@dataclass
class _Option:
    zone: int | None            # C-X's zone, None = unknown
    score: float
    half: str | None = None     # half of C-X's zone


def _dist(belief: DiscreteBelief | None, k: int) -> tuple[dict, float]:
    if belief is None or belief.empty:
        return {}, 1.0 / k
    return belief.distribution()


def _pair_options(profile: Profile, kind: str, zc_belief, zm_belief) -> list[_Option]:
    k = len(profile.zones.all_zones)
    pc, oc = _dist(zc_belief, k)
    pm, om = _dist(zm_belief, k)
    name = "C-" + kind
    valid = set(profile.machine_zones(CYAN))
    if kind[:2] in _SWAPPING:
        valid |= set(profile.machine_zones(MAGENTA))
    fixed = profile.fixed_zones.get(name)
    if fixed is not None:
        valid = {fixed}
    cands = {z for z in pc if z in valid}
    cands |= {profile.mirror_zone(z) for z in pm if profile.mirror_zone(z) in valid}
    if fixed is not None:
        cands.add(fixed)
    opts = []
    for z in sorted(cands):
        s = math.log(max(pc.get(z, oc), 1e-300)) + math.log(
            max(pm.get(profile.mirror_zone(z), om), 1e-300))
        opts.append(_Option(z, s, profile.zone_team(z)))
    # "somewhere nobody saw it", per half, so the one-swapped-per-kind rule still binds
    for half in (CYAN, MAGENTA):
        n_unknown = sum(1 for z in valid if z not in cands and profile.zone_team(z) == half)
        if n_unknown > 0:
            opts.append(_Option(None, math.log(n_unknown) + math.log(max(oc, 1e-300))
                                + math.log(max(om, 1e-300)), half))
    opts.sort(key=lambda o: -o.score)
    return opts


def _normalised(opts: list[_Option], chosen: _Option) -> float:
    top = opts[0].score
    total = sum(math.exp(o.score - top) for o in opts)
    return math.exp(chosen.score - top) / total


def consistent_set(profile: Profile, beliefs: dict) -> ConsistentSet:
    """The most probable consistent placement of all machines.

    ``beliefs``: machine name -> :class:`~teamserver.knowledge.kb.MachineBelief` (any
    subset; missing machines count as unobserved).
    """
    kinds = list(profile.machine_types)

    def prop(name: str, p: str):
        mb = beliefs.get(name)
        return None if mb is None else mb.props[p]

    options = {kd: _pair_options(profile, kd, prop("C-" + kd, M.ZONE), prop("M-" + kd, M.ZONE))
               for kd in kinds}
    order = sorted(kinds, key=lambda kd: len(options[kd]))
    best_rest = [0.0] * (len(order) + 1)
    for i in range(len(order) - 1, -1, -1):
        best_rest[i] = best_rest[i + 1] + options[order[i]][0].score
    groups = {g: [kd for kd in kinds if kd.startswith(g)] for g in _SWAPPING}

    best: dict = {"score": -math.inf, "choice": None}
    choice: dict[str, _Option] = {}
    occupied: set[int] = set()

    def swap_ok() -> bool:
        for members in groups.values():
            if len(members) < 2:
                continue
            chosen = [choice[kd] for kd in members if kd in choice]
            swapped = sum(1 for o in chosen if o.half == MAGENTA)
            if swapped > 1:
                return False
            if len(chosen) == len(members) and swapped != 1:
                return False
        return True

    def search(i: int, score: float) -> None:
        if score + best_rest[i] <= best["score"]:
            return
        if i == len(order):
            best["score"], best["choice"] = score, dict(choice)
            return
        kd = order[i]
        for opt in options[kd]:
            zs = () if opt.zone is None else (opt.zone, profile.mirror_zone(opt.zone))
            if any(z in occupied for z in zs):
                continue
            choice[kd] = opt
            if swap_ok():
                occupied.update(zs)
                search(i + 1, score + opt.score)
                occupied.difference_update(zs)
            del choice[kd]

    search(0, 0.0)
    result = ConsistentSet(score=best["score"])
    picked: dict[str, _Option] = best["choice"] or {
        kd: next((o for o in options[kd] if o.zone is None), options[kd][0]) for kd in kinds}
    for kd in kinds:
        opt = picked[kd]
        conf = _normalised(options[kd], opt)
        cname, mname = "C-" + kd, "M-" + kd
        zc = opt.zone
        zm = None if zc is None else profile.mirror_zone(zc)
        light, lconf = _shared_light(profile, prop(cname, M.LIGHT), prop(mname, M.LIGHT))
        (oc, ocf), (om, omf) = _rotations(profile, kd, zc, prop(cname, M.ORIENTATION),
                                          prop(mname, M.ORIENTATION))
        result.machines[cname] = MachineGuess(cname, zc, conf if zc is not None else 0.0, oc, ocf, light, lconf)
        result.machines[mname] = MachineGuess(mname, zm, conf if zm is not None else 0.0, om, omf, light, lconf)
        for name, z in ((cname, zc), (mname, zm)):
            mb = beliefs.get(name)
            est = None if mb is None else mb.estimate(M.ZONE)
            if est is not None and z is not None and est.value != z:
                result.conflicts.append(name)
    return result


def _shared_light(profile: Profile, bc, bm) -> tuple[tuple[str, ...] | None, float]:
    """Twins show the same light code: the code maximising P_C(l) * P_M(l)."""
    codes = [tuple(sorted(v)) for v in profile.light_codes.values()]
    if not codes:
        return None, 0.0
    k = len(codes)
    pc, oc = _dist(bc, k)
    pm, om = _dist(bm, k)
    if not pc and not pm:
        return None, 0.0
    joint = {c: pc.get(c, oc) * pm.get(c, om) for c in codes}
    total = sum(joint.values())
    best = max(codes, key=lambda c: (joint[c], repr(c)))
    return best, joint[best] / total


def _rotations(profile: Profile, kind: str, zc: int | None, bc, bm):
    """((C-X rotation, conf), (M-X rotation, conf)) from the mirrored-rotation rule."""
    step = profile.rotation_step_deg
    values = list(range(0, 360, step))
    k = len(values)
    pc, oc = _dist(bc, k)
    pm, om = _dist(bm, k)
    if (not pc and not pm) or zc is None:
        return (None, 0.0), (None, 0.0)
    cyan_half = profile.zone_team(zc) == CYAN      # is C-X the machine in the cyan half?
    p_cy, o_cy, p_mg, o_mg = (pc, oc, pm, om) if cyan_half else (pm, om, pc, oc)
    z_cyan_half = zc if cyan_half else profile.mirror_zone(zc)
    fixed = None
    if profile.year >= 2017:
        twin_zone, twin_rot = profile.mirror_placement("C-" + kind, z_cyan_half, 0)
        probe = profile.mirror_placement("C-" + kind, z_cyan_half, 90)[1]
        if twin_rot == probe:           # the twin's rotation does not follow: a wall case
            fixed = twin_rot
    if fixed is not None:
        r_cy = max(values, key=lambda r: (p_cy.get(r, o_cy), -r))
        conf_cy = p_cy.get(r_cy, o_cy) / sum(p_cy.get(r, o_cy) for r in values)
        pair = ((r_cy, conf_cy if p_cy else 0.0), (fixed, 1.0))
    else:
        joint = {r: p_cy.get(r, o_cy) * p_mg.get(profile.mirror_rotation(r), o_mg)
                 for r in values}
        total = sum(joint.values())
        r_cy = max(values, key=lambda r: (joint[r], -r))
        conf = joint[r_cy] / total
        pair = ((r_cy, conf), (profile.mirror_rotation(r_cy), conf))
    return pair if cyan_half else (pair[1], pair[0])
