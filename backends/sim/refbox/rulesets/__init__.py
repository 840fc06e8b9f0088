"""The rule sets of the simulated refbox, one module per rule set.

:mod:`.rcll2016` is the 2016 refbox (tag 2016-1), :mod:`.rcll2025` today's
(a subclass overriding what changed).  :func:`rules_for` picks the one
playing a profile; nothing else in the game core names a year.
"""
from __future__ import annotations

from .rcll2016 import Rules2016
from .rcll2025 import Rules2025

RULESETS = {"rcll2016": Rules2016, "rcll2025": Rules2025}


def rules_for(profile) -> Rules2016:
    """The rule set playing ``profile``; ValueError for a profile without one."""
    try:
        return RULESETS[profile.name]()
    except KeyError:
        raise ValueError(f"the simulated refbox does not play {profile.name!r} "
                         f"(it plays: {', '.join(RULESETS)})") from None


__all__ = ["Rules2016", "Rules2025", "RULESETS", "rules_for"]
