"""Who plays whom: the games of a round robin and the settings every game shares.

Each pair of configurations meets on every seed twice, once in each colour,
as in the planning competition's round robin: a layout that favours one
half of the field favours both teams once.  A game is plain data (a
:class:`Match`, a dict for the wire), so any executor can ship it to a
worker, and its ``key`` names it in the store.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from itertools import combinations

from ..teams import TeamSpec

#: the game settings a tournament may set, with their defaults (None: the rules')
SETTINGS = {"profile": "rcll2016", "setup": 10.0, "exploration": None, "production": None,
            "overtime": None, "robots": 3, "strategy": "algorithm1"}


@dataclass(frozen=True)
class Match:
    """One game: ``cyan`` and ``magenta`` (CONFIG texts), ``seed`` and the shared ``settings``."""

    cyan: str
    magenta: str
    seed: int
    settings: dict = field(default_factory=dict, compare=False, hash=False)

    @property
    def key(self) -> str:
        return f"{self.cyan} | {self.magenta} | {self.seed}"

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> Match:
        return cls(d["cyan"], d["magenta"], int(d["seed"]), dict(d.get("settings") or {}))


def normalise(configs: list[str]) -> list[str]:
    """Each CONFIG in its one written form (``ValueError`` for a bad one or
    the same configuration twice)."""
    out = [str(TeamSpec.parse(c)) for c in configs]
    if len(out) < 2:
        raise ValueError("a tournament needs at least two configurations")
    twice = sorted({c for c in out if out.count(c) > 1})
    if twice:
        raise ValueError(f"configuration {twice[0]} given twice")
    if any(TeamSpec.parse(c).external for c in out):
        raise ValueError("an external team cannot play a tournament (it joins one game over the network)")
    return out


def settings(**given) -> dict:
    """The shared game settings: ``given`` over :data:`SETTINGS` (``ValueError`` for an unknown one)."""
    unknown = set(given) - set(SETTINGS)
    if unknown:
        raise ValueError(f"unknown tournament setting {', '.join(sorted(unknown))}")
    return {k: given.get(k, v) if given.get(k) is not None else v for k, v in SETTINGS.items()}


def round_robin(configs: list[str], seeds: list[int], shared: dict) -> list[Match]:
    """Every pair on every seed in both colours, seed by seed (a tournament
    stopped early has played whole seeds of every pair first)."""
    configs = normalise(configs)
    return [Match(a, b, s, dict(shared)) for s in seeds
            for x, y in combinations(configs, 2) for a, b in ((x, y), (y, x))]
