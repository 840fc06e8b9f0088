"""The game as ``rll-bt sim`` reports it, read in the refbox's process or from its snapshot.

:class:`GameView` reads a live :class:`~.game.RefboxGame`; :func:`snapshot`
turns it into plain JSON, what ``rll-bt refbox sim --snapshot FILE``
rewrites; :class:`SnapshotView` reads that file back in another process
(the world's, with ``rll-bt sim --processes``), again whenever the refbox
rewrote it.  Both answer ``status()``, ``awards()``, ``deliveries()``,
``station_states()``, ``light_codes()`` (2016: each station's exploration
light colours, sorted), ``orders()``, ``station_log()`` (every station
state change: ``{"phase", "game_time", "machine", "from", "to", "reason",
"cause"}``) and ``tally(team)`` (stations gone BROKEN by cause, referee calls).

The snapshot: ``{"status": GameStatus fields, "awards": [Award fields],
"deliveries": [Delivery fields], "stations": {machine: {"state", "light"}},
"orders": [order fields], "station_log": [...], "tally": {team: {"broken",
"referee"}}}`` plus what the writer adds
(the CLI: ``pid``, ``now`` on its monotonic clock, ``link`` counts).
"""
from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

from rll_bt.contracts import Award, Delivery, GameStatus, Tally

from . import events as E
from . import referee

TEAMS = ("CYAN", "MAGENTA")


class GameView:
    """``game`` (a :class:`~.game.RefboxGame`) as plain values."""

    def __init__(self, game):
        self.game = game

    def status(self) -> GameStatus:
        g = self.game
        return GameStatus(g.phase, g.state, g.game_time, g.timing.length(g.phase), {t: g.points(t) for t in TEAMS})

    def awards(self) -> list[Award]:
        return list(self.game.ledger.entries)       # the ledger keeps Award records

    def deliveries(self) -> list[Delivery]:
        return [Delivery(e.team, e.game_time, int(e.points or 0), e.data.get("order"), str(e.data.get("how", "")))
                for e in self.game.events if e.kind == E.DELIVERY]

    def station_states(self) -> dict[str, str]:
        return {name: st.state for name, st in self.game.stations.items()}

    def light_codes(self) -> dict[str, tuple[str, ...]]:
        g = self.game
        if not hasattr(g.exploration, "code_of"):          # 2016 only: the type's light code
            return {}
        return {name: tuple(sorted(g.profile.light_code(g.exploration.code_of(name)))) for name in g.stations}

    def orders(self) -> list[dict]:
        out = []
        for o in self.game.orders:
            d = {f.name: getattr(o, f.name) for f in dataclasses.fields(o)}
            d["rings"] = list(d["rings"])
            out.append(d)
        return out

    def station_log(self) -> list[dict]:
        return [{"phase": e.phase, "game_time": round(e.game_time, 3), "machine": e.machine,
                 "from": e.data.get("previous"), "to": e.data.get("state"), "reason": e.data.get("reason"),
                 "cause": e.data.get("cause")}
                for e in self.game.events if e.kind == E.MACHINE]

    def tally(self, team: str) -> Tally:
        return referee.tally(self.game.events, team)


def snapshot(view) -> dict:
    """Everything a view answers, as plain JSON."""
    lights = view.light_codes()
    return {"status": dataclasses.asdict(view.status()),
            "awards": [dataclasses.asdict(a) for a in view.awards()],
            "deliveries": [dataclasses.asdict(d) for d in view.deliveries()],
            "stations": {m: {"state": s, "light": list(lights.get(m, ()))} for m, s in view.station_states().items()},
            "orders": view.orders(), "station_log": view.station_log(),
            "tally": {t: dataclasses.asdict(view.tally(t)) for t in TEAMS}}


def write_snapshot(path: Path, snap: dict) -> None:
    """Replace the snapshot file at ``path`` at once (a reader never sees half of it)."""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(snap, default=str))
    os.replace(tmp, path)


class SnapshotView:
    """The snapshot file at ``path`` (None: none yet), read again whenever it
    changed; before the first one the game is in PRE_GAME with nothing in it."""

    def __init__(self, path: str | Path | None):
        self.path = Path(path) if path is not None else None
        self._key = None
        self._data: dict = {}

    def data(self) -> dict:
        if self.path is None:
            return self._data
        try:
            st = os.stat(self.path)
            key = (st.st_ino, st.st_mtime_ns, st.st_size)
            if key != self._key:
                self._data, self._key = json.loads(self.path.read_text()), key
        except (OSError, ValueError):
            pass                       # not written yet, or being replaced: the last one read
        return self._data

    @property
    def ready(self) -> bool:
        """Whether the refbox wrote its first snapshot."""
        return bool(self.data())

    def status(self) -> GameStatus:
        s = self.data().get("status")
        if s is None:
            return GameStatus("PRE_GAME", "WAIT_START", 0.0, None, dict.fromkeys(TEAMS, 0))
        return GameStatus(**s)

    def awards(self) -> list[Award]:
        return [Award(**a) for a in self.data().get("awards", [])]

    def deliveries(self) -> list[Delivery]:
        return [Delivery(**d) for d in self.data().get("deliveries", [])]

    def station_states(self) -> dict[str, str]:
        return {m: d["state"] for m, d in self.data().get("stations", {}).items()}

    def light_codes(self) -> dict[str, tuple[str, ...]]:
        return {m: tuple(d["light"]) for m, d in self.data().get("stations", {}).items() if d.get("light")}

    def orders(self) -> list[dict]:
        return list(self.data().get("orders", []))

    def station_log(self) -> list[dict]:
        return list(self.data().get("station_log", []))

    def tally(self, team: str) -> Tally:
        return Tally(**self.data().get("tally", {}).get(team, {}))
