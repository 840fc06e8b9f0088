"""A stored game: the field and the orders that make two games identical.

:class:`StoredGame` holds what the refbox draws at random for a game and a
team's result depends on: where each machine stands (zone and rotation),
the orders (complexity, colours, quantity, delivery window, gate,
activation time, competitive, standing or overtime), the ring colours'
costs, each ring station's two colours, and the machines' down periods
(production game seconds), and where a layout put a machine off its zone's
centre (2016), its exact centre (``poses``).  It is saved as JSON
(:meth:`StoredGame.save`, :func:`load_game`) and read from the refbox's own
game reports (:meth:`StoredGame.from_report`, :func:`read_refbox_games`),
and gives the world its field (:meth:`StoredGame.layout`).
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

FORMAT = "rll-bt stored game"
VERSION = 1


class StoredGameError(ValueError):
    """A stored game that cannot be read (the message names the file and key)."""


@dataclass(frozen=True)
class StoredOrder:
    id: int
    complexity: str                       # "C0".."C3"
    base: str                             # "BASE_RED" ...
    rings: tuple[str, ...]
    cap: str
    quantity: int
    delivery: tuple[int, int]             # game seconds of production: begin, end
    gate: int
    activate_at: int = 0
    competitive: bool = False
    standing: bool = False                # open for the whole production (2016's #1, 2025's #1 and #2)
    overtime: bool = False                # only in overtime


@dataclass(frozen=True)
class StoredGame:
    profile: str
    machines: dict[str, tuple[str, int]]                      # machine -> (zone name, rotation deg)
    orders: tuple[StoredOrder, ...] = ()
    ring_costs: dict[str, int] = field(default_factory=dict)  # ring colour -> additional bases
    ring_colors: dict[str, tuple[str, str]] = field(default_factory=dict)   # RS -> its two colours
    down_periods: dict[str, tuple[float, float]] = field(default_factory=dict)
    name: str = ""
    poses: dict[str, tuple[float, float]] = field(default_factory=dict)    # machine -> centre x, y (m)

    # -- JSON ----------------------------------------------------------------------
    def to_dict(self) -> dict:
        d = asdict(self)
        # machines in their field's order (a world iterates its stations in it)
        d["machines"] = {m: {"zone": z, "rotation": r} for m, (z, r) in self.machines.items()}
        d["ring_colors"] = {m: list(c) for m, c in sorted(self.ring_colors.items())}
        d["down_periods"] = {m: list(p) for m, p in sorted(self.down_periods.items())}
        d["poses"] = {m: list(p) for m, p in sorted(self.poses.items())}
        for o in d["orders"]:
            o["rings"], o["delivery"] = list(o["rings"]), list(o["delivery"])
        return {"format": FORMAT, "version": VERSION, **d}

    @classmethod
    def from_dict(cls, d: dict, where: str = "stored game") -> StoredGame:
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise StoredGameError(f"{where}: not an rll-bt stored game (no \"format\": \"{FORMAT}\")")
        if d.get("version") != VERSION:
            raise StoredGameError(f"{where}: version {d.get('version')!r} (this rll-bt reads {VERSION})")
        try:
            game = cls(
                profile=str(d["profile"]),
                machines={str(m): (str(v["zone"]), int(v["rotation"])) for m, v in d["machines"].items()},
                orders=tuple(StoredOrder(int(o["id"]), str(o["complexity"]), str(o["base"]),
                                         tuple(map(str, o["rings"])), str(o["cap"]), int(o["quantity"]),
                                         (int(o["delivery"][0]), int(o["delivery"][1])), int(o["gate"]),
                                         int(o.get("activate_at", 0)), bool(o.get("competitive", False)),
                                         bool(o.get("standing", False)), bool(o.get("overtime", False)))
                             for o in d.get("orders", ())),
                ring_costs={str(k): int(v) for k, v in d.get("ring_costs", {}).items()},
                ring_colors={str(m): (str(c[0]), str(c[1])) for m, c in d.get("ring_colors", {}).items()},
                down_periods={str(m): (float(p[0]), float(p[1])) for m, p in d.get("down_periods", {}).items()},
                name=str(d.get("name", "")),
                poses={str(m): (float(p[0]), float(p[1])) for m, p in d.get("poses", {}).items()})
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as e:
            raise StoredGameError(f"{where}: malformed ({type(e).__name__}: {e})") from None
        game.check()
        return game

    def save(self, path: str) -> None:
        with open(path, "w") as f:
            json.dump(self.to_dict(), f, indent=1)
            f.write("\n")

    # -- meaning ---------------------------------------------------------------------
    def check(self) -> None:
        """StoredGameError unless every zone, rotation and colour makes sense in the profile."""
        from rll_bt import rules
        from rll_bt.rules.profile import BASE_COLORS, CAP_COLORS, RING_COLORS
        try:
            prof = rules.profile(self.profile)
        except ValueError as e:
            raise StoredGameError(f"stored game: {e}") from None
        for m, (zone, rot) in self.machines.items():
            try:
                prof.zone_number(zone)
            except (KeyError, ValueError):
                raise StoredGameError(f"stored game: {m} in unknown zone {zone!r}") from None
            if prof.rotation_step_deg and rot % prof.rotation_step_deg:
                raise StoredGameError(f"stored game: {m} rotation {rot} is not a multiple of "
                                      f"{prof.rotation_step_deg}")
        for m, (x, y) in self.poses.items():
            if m not in self.machines:
                raise StoredGameError(f"stored game: a pose for {m}, which has no zone")
            if prof.zone_at(x, y) != prof.zone_number(self.machines[m][0]):
                raise StoredGameError(f"stored game: {m} at ({x:.2f}, {y:.2f}) is not in its zone "
                                      f"{self.machines[m][0]}")
        for o in self.orders:
            if o.base not in BASE_COLORS or o.cap not in CAP_COLORS or any(r not in RING_COLORS for r in o.rings):
                raise StoredGameError(f"stored game: order {o.id} has an unknown colour")
            if o.complexity != f"C{len(o.rings)}":
                raise StoredGameError(f"stored game: order {o.id} is {o.complexity} with {len(o.rings)} rings")

    def layout(self, seed: int | None = None):
        """The world's :class:`~backends.sim.layout.FieldLayout` of this field:
        every machine at its stored pose, else at its zone's centre, turned by
        its rotation."""
        from rll_bt import rules

        from ..layout import FieldLayout
        prof = rules.profile(self.profile)
        machines = {}
        for m, (zone, rot) in self.machines.items():
            x, y = self.poses.get(m) or prof.zone_centre(prof.zone_number(zone))
            machines[m] = {"zone": prof.zone_number(zone), "rotation": rot % 360, "x": x, "y": y}
        return FieldLayout.from_dict({"profile": prof.name, "seed": seed, "machines": machines})

    @classmethod
    def from_machine_info(cls, machine_info, profile: str = "rcll2025") -> StoredGame:
        """The field a refbox announces: a MachineInfo (message of the profile's
        set) whose machines carry ``zone`` and ``rotation`` (the refbox sends
        the ground truth once the exploration period is over), with each ring
        station's colours.  Machines without a zone are left out."""
        from rll_bt import msgs
        zone_enum = msgs.message_set(profile).enum("Zone")
        ring_enum = msgs.message_set(profile).enum("RingColor")
        machines, colors = {}, {}
        for m in machine_info.machines:
            if m.HasField("zone") and m.zone:
                machines[m.name] = (zone_enum.Name(m.zone), int(m.rotation))
            if len(m.ring_colors) >= 2:
                colors[m.name] = (ring_enum.Name(m.ring_colors[0]), ring_enum.Name(m.ring_colors[1]))
        game = cls(profile, machines, ring_colors=colors, name="from MachineInfo")
        game.check()
        return game

    # -- the refbox's game reports ----------------------------------------------------------
    @classmethod
    def from_report(cls, report: dict, profile: str = "rcll2025") -> StoredGame:
        """The game a refbox game report (a ``game_report`` document) describes."""
        where = f"game report {report.get('report-name', report.get('_id', '?'))}"
        try:
            machines, colors, downs = {}, {}, {}
            for m in report["machines"]:
                machines[m["name"]] = (m["zone"], int(m["rotation"]))
                if m.get("mtype") == "RS" and m.get("rs-ring-colors"):
                    colors[m["name"]] = tuple(m["rs-ring-colors"][:2])
                dp = m.get("down-period", [-1.0, -1.0])
                if dp and dp[0] >= 0:
                    downs[m["name"]] = (float(dp[0]), float(dp[1]))
            # a report has no standing or overtime flag: the production it was played with
            # ends where its orders open from the start end; those stand, one opening at its
            # end is the overtime order
            windows = [(int(o["delivery-period"][0]), int(o["delivery-period"][1])) for o in report.get("orders", ())]
            production = max((e for b, e in windows if b == 0), default=None)
            if production is None:
                from rll_bt import rules
                production = int(rules.profile(profile).phases.production)
            orders = tuple(StoredOrder(
                int(o["id"]), str(o["complexity"]), str(o["base-color"]), tuple(o.get("ring-colors", ())),
                str(o["cap-color"]), int(o["quantity-requested"]),
                (int(o["delivery-period"][0]), int(o["delivery-period"][1])), int(o["delivery-gate"]),
                int(o.get("activate-at", 0)), str(o.get("competitive", "FALSE")).upper() == "TRUE",
                standing=int(o["delivery-period"][0]) == 0 and int(o["delivery-period"][1]) >= production,
                overtime=int(o["delivery-period"][0]) >= production)
                for o in report.get("orders", ()))
            costs = {str(r["color"]): int(r["req-bases"]) for r in report.get("ring-specs", ())}
        except (KeyError, TypeError, ValueError, IndexError) as e:
            raise StoredGameError(f"{where}: malformed ({type(e).__name__}: {e})") from None
        game = cls(profile, machines, orders, costs, colors, downs, str(report.get("report-name", "")))
        game.check()
        return game


def load_game(path: str) -> StoredGame:
    """A stored game from ``path``: rll-bt's JSON, or the first game report
    of a refbox archive (``mongodump --archive``, gzipped or not)."""
    try:
        with open(path, "rb") as f:
            head = f.read(4)
    except OSError as e:
        raise StoredGameError(f"{path}: {e.strerror or e}") from None
    if head[:2] == b"\x1f\x8b" or head == b"\x6d\xe2\x99\x81":
        games = read_refbox_games(path)
        if not games:
            raise StoredGameError(f"{path}: the archive holds no game report")
        return games[0]
    try:
        with open(path) as f:
            data = json.load(f)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise StoredGameError(f"{path}: not JSON ({e})") from None
    return StoredGame.from_dict(data, path)


def read_refbox_games(path_or_bytes, profile: str = "rcll2025") -> list[StoredGame]:
    """Every game of a refbox archive of game reports (e.g. the refbox's
    ``benchmarks/rcll100.gz``), in the archive's order."""
    from .archive import ArchiveError, game_reports
    try:
        reports = game_reports(path_or_bytes)
    except ArchiveError as e:
        raise StoredGameError(str(e)) from None
    return [StoredGame.from_report(r, profile) for r in reports]


__all__ = ["StoredGame", "StoredGameError", "StoredOrder", "load_game", "read_refbox_games"]
