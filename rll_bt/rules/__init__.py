"""Rules profiles: ``rcll2016`` (the default, the paper's rules) and ``rcll2025``.

    from rll_bt import rules
    p = rules.profile("rcll2016")
    p.zone_at(3.1, 2.0)         # -> 6  (Z6)
    p.zone_centre(9)            # -> (5.0, 0.75)
    p.tag_ids("C-BS")           # -> (65, 66)
    p.machine_for_tag(66)       # -> ("C-BS", "OUTPUT")

Everything that differs between rule sets lives here as data and pure
functions; see :class:`rll_bt.rules.profile.Profile`.
"""
from __future__ import annotations

from . import rcll2016, rcll2025
from .geometry import MPS, ROBOT, WORKPIECE, MpsGeometry, RobotGeometry, WorkpieceGeometry
from .machines import BROKEN_TIME, MPS_TIMES, PREPARED_BLINK_TIME, WAIT_IDLE_TIME, MachineTimes
from .profile import (
    BASE_COLORS,
    CAP_COLORS,
    LIGHTS,
    PREFIX,
    RING_COLORS,
    TEAMS,
    OrderShape,
    Phases,
    Profile,
    Scoring,
    machine_team,
    machine_type,
    mirror_machine_name,
    other_team,
    rotation_to_theta,
    theta_to_rotation,
)
from .zones import CYAN, MAGENTA, Rect

DEFAULT = "rcll2016"
_PROFILES = {p.name: p for p in (rcll2016.PROFILE, rcll2025.PROFILE)}
PROFILES = tuple(_PROFILES)


def profile(name: str | None = None) -> Profile:
    """The profile called ``name`` (default ``rcll2016``)."""
    name = name or DEFAULT
    try:
        return _PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown rules profile {name!r} (known: {', '.join(PROFILES)})") from None


__all__ = [
    "profile", "PROFILES", "DEFAULT", "Profile", "Phases", "Scoring", "OrderShape", "Rect",
    "CYAN", "MAGENTA", "TEAMS", "PREFIX", "RING_COLORS", "BASE_COLORS", "CAP_COLORS", "LIGHTS",
    "machine_team", "machine_type", "mirror_machine_name", "other_team",
    "rotation_to_theta", "theta_to_rotation",
    "MPS", "ROBOT", "WORKPIECE", "MpsGeometry", "RobotGeometry", "WorkpieceGeometry",
    "MachineTimes", "MPS_TIMES", "BROKEN_TIME", "WAIT_IDLE_TIME", "PREPARED_BLINK_TIME",
]
