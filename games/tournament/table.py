"""The tournament's table, as the planning competition printed it, and its per-game rows.

:func:`standings` counts, per configuration, games, wins, losses, draws,
points for and against (summed over its games) and its best game (most
points, with the opponent, colour and seed); rows with ``error`` are left
out and counted apart.  Ordered by wins, then point difference, then name.
"""
from __future__ import annotations

import csv
import io

COLORS = ("cyan", "magenta")


def _played(rows) -> list[dict]:
    return [r for r in rows if not r.get("error")]


def standings(configs: list[str], rows) -> list[dict]:
    table = {c: {"config": c, "games": 0, "wins": 0, "losses": 0, "draws": 0, "points_for": 0,
                 "points_against": 0, "best": None} for c in configs}
    for r in sorted(_played(rows), key=lambda r: (r["seed"], r["cyan"], r["magenta"])):
        for color, other in (("cyan", "magenta"), ("magenta", "cyan")):
            me = table.get(r[color])
            if me is None:
                continue
            mine, theirs = r["points"][color], r["points"][other]
            me["games"] += 1
            me["points_for"] += mine
            me["points_against"] += theirs
            if r["winner"] is None:
                me["draws"] += 1
            elif r["winner"] == r[color]:
                me["wins"] += 1
            else:
                me["losses"] += 1
            if me["best"] is None or mine > me["best"]["points"]:
                me["best"] = {"points": mine, "against": theirs, "opponent": r[other], "color": color,
                              "seed": r["seed"]}
    return sorted(table.values(), key=lambda s: (-s["wins"], -(s["points_for"] - s["points_against"]),
                                                 s["config"]))


def render(configs: list[str], rows, *, planned: int | None = None) -> str:
    """The standings as text, with how many games are in it (and failed)."""
    st = standings(configs, rows)
    width = max(len("configuration"), *(len(s["config"]) for s in st))
    head = (f"{'configuration':<{width}}  games  wins  losses  draws  points for  against  "
            f"best game")
    lines = [head, "-" * len(head)]
    for s in st:
        b = s["best"]
        best = (f"{b['points']}:{b['against']} vs {b['opponent']} ({b['color']}, seed {b['seed']})"
                if b else "-")
        lines.append(f"{s['config']:<{width}}  {s['games']:5d}  {s['wins']:4d}  {s['losses']:6d}  "
                     f"{s['draws']:5d}  {s['points_for']:10d}  {s['points_against']:7d}  {best}")
    played, failed = len(_played(rows)), len(rows) - len(_played(rows))
    foot = f"{played} games" + (f" of {planned}" if planned is not None else "")
    if failed:
        foot += f", {failed} failed (see games.csv)"
    return "\n".join([*lines, "", foot])


ROW_FIELDS = ("seed", "cyan", "magenta", "cyan_points", "magenta_points", "winner", "cyan_delivered",
              "magenta_delivered", "collisions_between_teams", "cyan_collisions_within",
              "magenta_collisions_within", "collisions_with_stations", "collisions_with_walls",
              "sim_time", "wall_time", "host", "error")


def flat(r: dict) -> dict:
    pts = r.get("points") or {}
    dl = r.get("deliveries") or {}
    own = r.get("collisions_within_teams") or {}     # rows stored before these fields: left empty
    hit = r.get("collisions_with") or {}
    return {"seed": r["seed"], "cyan": r["cyan"], "magenta": r["magenta"],
            "cyan_points": pts.get("cyan"), "magenta_points": pts.get("magenta"),
            "winner": r.get("winner") or ("" if r.get("error") else "draw"),
            "cyan_delivered": dl.get("cyan"), "magenta_delivered": dl.get("magenta"),
            "collisions_between_teams": r.get("collisions_between_teams"),
            "cyan_collisions_within": own.get("cyan"), "magenta_collisions_within": own.get("magenta"),
            "collisions_with_stations": hit.get("station"), "collisions_with_walls": hit.get("wall"),
            "sim_time": r.get("sim_time"),
            "wall_time": r.get("wall_time"), "host": r.get("host"), "error": r.get("error") or ""}


def games_csv(rows) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, ROW_FIELDS, lineterminator="\n")
    w.writeheader()
    for r in sorted(rows, key=lambda r: (r["seed"], r["cyan"], r["magenta"])):
        w.writerow(flat(r))
    return buf.getvalue()


def games_text(rows) -> str:
    """One line per game: seed, cyan : magenta with the scores, the winner."""
    out = []
    for r in sorted(rows, key=lambda r: (r["seed"], r["cyan"], r["magenta"])):
        if r.get("error"):
            out.append(f"seed {r['seed']:3d}  {r['cyan']} : {r['magenta']}  failed: {r['error']}")
            continue
        p = r["points"]
        out.append(f"seed {r['seed']:3d}  {r['cyan']} {p['cyan']} : {p['magenta']} {r['magenta']}  "
                   f"winner {r['winner'] or 'draw'}")
    return "\n".join(out)
