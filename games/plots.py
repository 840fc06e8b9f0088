"""The game's pictures, drawn headless with matplotlib (Agg).

- ``field.png``: zones, the stations (footprint in the team colour, name,
  state at the end) and every robot's path (ground truth, field frame, m).
- ``timeline.png``: per robot, the task trees it ran (coloured by task kind,
  hatched where it failed); per own station, its state over time; phase
  boundaries as vertical lines.  x is simulated seconds.
- ``score.png``: our points over time, with the phase boundaries.

A game of two teams draws both: every robot's path (cyan's solid, magenta's
dashed, named C-R1.. and M-R1..), both teams' robots and stations in the
timeline, both scores.  Functions taking ``recording`` also take a list of
recordings (one per team).
"""
from __future__ import annotations

import math
from pathlib import Path

TEAM_COLOR = {"CYAN": "#16b7d0", "MAGENTA": "#d0169a"}
ROBOT_COLORS = ("#e6550d", "#31a354", "#756bb1", "#636363", "#3182bd", "#e7ba52")
TASK_COLORS = {"explore_zone": "#9ecae1", "get_workpiece": "#fd8d3c", "put_workpiece": "#fdae6b",
               "retrieve_cap": "#74c476", "mount_cap": "#31a354", "mount_ring": "#9e9ac8",
               "deliver": "#de2d26", "discard": "#969696", "report_machines": "#c6dbef", "go_to": "#fdd0a2"}
STATE_COLORS = {"IDLE": "#e0e0e0", "PREPARED": "#ffe082", "PROCESSING": "#ffb300",
                "READY-AT-OUTPUT": "#66bb6a", "WAIT-IDLE": "#aed581", "BROKEN": "#e53935",
                "DOWN": "#8e24aa"}


def _plt():
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def _recordings(recording) -> list:
    return list(recording) if isinstance(recording, list | tuple) else [recording]


def _robot_label(rec, robot, many: bool) -> str:
    return f"{rec.team[0]}-R{robot}" if many else f"R{robot}"


def _phase_lines(ax, phases, end: float) -> None:
    for i, (t, name) in enumerate(phases):      # labels staggered: a short SETUP would overlap
        ax.axvline(t, color="#555555", lw=0.8, ls="--")
        ax.text(t, 1.0 + 0.045 * (i % 2), f" {name}", transform=ax.get_xaxis_transform(), fontsize=7,
                va="bottom", color="#555555")
    ax.set_xlim(0, max(end, 1.0))


def draw_field(profile, stations: dict, recording, path: str | Path) -> Path:
    """Zones, stations and robot paths; returns the path written."""
    plt = _plt()
    from matplotlib.patches import Polygon, Rectangle
    f = profile.field
    fig, ax = plt.subplots(figsize=(2.0 + (f.x_max - f.x_min) * 1.0, 1.5 + (f.y_max - f.y_min + 1.2) * 1.0))
    try:
        for zone in profile.zones.all_zones:
            b = profile.zones.bounds(zone)
            ax.add_patch(Rectangle((b.x_min, b.y_min), b.x_max - b.x_min, b.y_max - b.y_min,
                                   facecolor=TEAM_COLOR[profile.zone_team(zone)], alpha=0.05,
                                   edgecolor="#aaaaaa", lw=0.5))
            ax.text(b.x_min + 0.04, b.y_max - 0.04, profile.zone_name(zone), fontsize=5,
                    color="#888888", va="top")
        for team, r in profile.insertion.items():
            ax.add_patch(Rectangle((r.x_min, r.y_min), r.x_max - r.x_min, r.y_max - r.y_min,
                                   facecolor=TEAM_COLOR[team], alpha=0.15, edgecolor="#666666", lw=0.6))
        hx, hy = profile.mps.depth / 2.0, profile.mps.width / 2.0
        for name, st in sorted(stations.items()):
            c, s = math.cos(st.pose.theta), math.sin(st.pose.theta)
            corners = [(st.pose.x + c * x - s * y, st.pose.y + s * x + c * y)
                       for x, y in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]
            ax.add_patch(Polygon(corners, closed=True, facecolor=TEAM_COLOR.get(st.team, "#999999"),
                                 alpha=0.7, edgecolor="black", lw=0.8))
            ax.text(st.pose.x, st.pose.y, name, fontsize=6, ha="center", va="center", weight="bold")
        recs = _recordings(recording)
        many = len(recs) > 1
        paths = [(rec, robot, pts) for rec in recs for robot, pts in sorted(rec.paths.items())]
        for i, (rec, robot, pts) in enumerate(paths):
            if not pts:
                continue
            xs, ys = [p[1] for p in pts], [p[2] for p in pts]
            color = ROBOT_COLORS[i % len(ROBOT_COLORS)]
            ax.plot(xs, ys, color=color, lw=0.9, alpha=0.8, ls="--" if rec.team == "MAGENTA" and many else "-",
                    label=_robot_label(rec, robot, many))
            ax.plot(xs[0], ys[0], "o", color=color, ms=4)
            ax.plot(xs[-1], ys[-1], "s", color=color, ms=4)
        ax.add_patch(Rectangle((f.x_min, f.y_min), f.x_max - f.x_min, f.y_max - f.y_min, fill=False,
                               edgecolor="black", lw=1.2))
        ax.set_aspect("equal")
        ax.set_xlim(f.x_min - 0.3, f.x_max + 0.3)
        low = min([f.y_min] + [r.y_min for r in profile.insertion.values()])
        ax.set_ylim(low - 0.3, f.y_max + 0.3)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{profile.name}: stations and robot paths (o start, square end)", fontsize=9)
        if paths:
            ax.legend(loc="upper right", fontsize=7, ncol=2 if many else 1)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)


def draw_timeline(recording, team: str | None, end: float, path: str | Path) -> Path:
    """Robot tasks and own station states over simulated time (``recording``:
    one team's, ``team`` its colour; or a list of recordings, each team's
    robots and stations)."""
    plt = _plt()
    from matplotlib.patches import Patch
    recs = _recordings(recording)
    many = len(recs) > 1
    robots = [(rec, r) for rec in recs for r in sorted(rec.tasks)]
    teams = [rec.team for rec in recs] if many or team is None else [team]
    stations = [n for t in teams for n in sorted(n for n in recs[0].stations if n.startswith(t[0] + "-"))]
    rows = [_robot_label(rec, r, many) for rec, r in robots] + stations
    fig, ax = plt.subplots(figsize=(12, 1.2 + 0.42 * max(len(rows), 1)))
    try:
        for i, (rec, r) in enumerate(robots):
            for run in rec.tasks[r]:
                stop = run["end"] if run["end"] is not None else end
                ax.barh(i, stop - run["start"], left=run["start"], height=0.7,
                        color=TASK_COLORS.get(run["kind"], "#bbbbbb"), edgecolor="#333333", lw=0.3,
                        hatch="xx" if run.get("outcome") == "FAILED" else None)
        base = len(robots)
        for j, name in enumerate(stations):
            hist = recs[0].stations[name]
            for k, (t, state) in enumerate(hist):
                stop = hist[k + 1][0] if k + 1 < len(hist) else end
                ax.barh(base + j, stop - t, left=t, height=0.7, color=STATE_COLORS.get(state, "#ffffff"),
                        edgecolor="none")
        for rec in recs:
            for ev in rec.events:
                ax.axvline(ev["t"], color="#d62728", lw=0.8)
                ax.text(ev["t"], -0.9, (f"{rec.team[0]}: " if many else "") + ev["what"], fontsize=6,
                        color="#d62728", rotation=0)
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels(rows, fontsize=8)
        ax.invert_yaxis()
        _phase_lines(ax, recs[0].phases, end)
        ax.set_xlabel("simulated time (s)")
        kinds = sorted({run["kind"] for rec in recs for runs in rec.tasks.values() for run in runs})
        states = sorted({s for n in stations for _, s in recs[0].stations[n]})
        handles = [Patch(color=TASK_COLORS.get(k, "#bbbbbb"), label=k) for k in kinds]
        handles += [Patch(color=STATE_COLORS.get(s, "#ffffff"), label=s) for s in states]
        if handles:
            ax.legend(handles=handles, fontsize=6, ncol=min(len(handles), 7), loc="upper center",
                      bbox_to_anchor=(0.5, -0.18))
        ax.set_title("robot tasks (hatched: failed) and station states", fontsize=9, pad=18)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)


def draw_score(recording, end: float, path: str | Path, labels: dict | None = None) -> Path:
    """Points over simulated time (of each team; ``labels``: colour -> the CONFIG it played)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(9, 3.6))
    try:
        recs = _recordings(recording)
        for rec in recs:
            ts = [s["t"] for s in rec.samples]
            pts = [s["points"] for s in rec.samples]
            ax.step(ts, pts, where="post", color=TEAM_COLOR.get(rec.team, "black"), lw=1.5,
                    label=(labels or {}).get(rec.team, rec.team))
        _phase_lines(ax, recs[0].phases, end)
        ax.set_xlabel("simulated time (s)")
        ax.set_ylabel("points")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        if len(recs) > 1:
            ax.legend(loc="upper left", fontsize=8)
        ax.set_title(" against ".join(f"{rec.team} {(labels or {}).get(rec.team, '')}".strip() for rec in recs)
                     + " score", fontsize=9, pad=18)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)


def draw_all(profile, result, out: str | Path) -> list[Path]:
    out = Path(out)
    recs = list((getattr(result, "recordings", None) or {}).values()) or [result.recording]
    rec = recs if len(recs) > 1 else recs[0]
    labels = getattr(result, "labels", None) or {}
    return [draw_field(profile, result.stations, rec, out / "field.png"),
            draw_timeline(rec, None if len(recs) > 1 else recs[0].team, result.sim_time, out / "timeline.png"),
            draw_score(rec, result.sim_time, out / "score.png", labels if len(recs) > 1 else None)]
