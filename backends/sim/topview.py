"""A top view of a field layout drawn with matplotlib (no PyBullet needed):
zones with their names, walls, insertion areas, robot start lanes, and each
station as its footprint in the team colour with an arrow from its output to
its input side, its name, and the tag ids on its input (I) and output (O)
faces.  Field frame, metres.
"""
from __future__ import annotations

import math

from rll_bt.rules import CYAN, TEAMS, Profile, machine_team

from .fieldgeom import footprint, start_pose, walls
from .layout import FieldLayout

TEAM_COLOR = {CYAN: "#16b7d0", "MAGENTA": "#d0169a"}


def draw_layout(profile: Profile, layout: FieldLayout, path: str, title: str | None = None,
                dpi: int = 110) -> str:
    """Write the PNG to ``path`` and return the path."""
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrow, Polygon, Rectangle

    f = profile.field
    fig_w = 2.0 + (f.x_max - f.x_min) * 1.05
    fig_h = 1.6 + (f.y_max - f.y_min + 1.5) * 1.05
    fig, ax = plt.subplots(figsize=(fig_w, fig_h))
    try:
        for zone in profile.zones.all_zones:
            b = profile.zones.bounds(zone)
            tint = TEAM_COLOR[profile.zone_team(zone)]
            ax.add_patch(Rectangle((b.x_min, b.y_min), b.x_max - b.x_min, b.y_max - b.y_min,
                                   facecolor=tint, alpha=0.06, edgecolor="#999999", lw=0.6))
            ax.text(b.x_min + 0.05, b.y_max - 0.05, profile.zone_name(zone), fontsize=6,
                    color="#777777", ha="left", va="top")
        for team, r in profile.insertion.items():
            ax.add_patch(Rectangle((r.x_min, r.y_min), r.x_max - r.x_min, r.y_max - r.y_min,
                                   facecolor="none", edgecolor=TEAM_COLOR[team], hatch="//", lw=1.0))
            ax.text(r.centre[0], r.y_min + 0.05, "insertion", fontsize=7, ha="center", va="bottom",
                    color=TEAM_COLOR[team])
        for w in walls(profile):
            ax.add_patch(Rectangle((w.x_min, w.y_min), w.x_max - w.x_min, w.y_max - w.y_min,
                                   facecolor="#333333", edgecolor="none"))
        for team in TEAMS:
            for n in (1, 2, 3):
                s = start_pose(profile, team, n)
                ax.add_patch(plt.Circle((s.x, s.y), profile.robot.radius, facecolor="none",
                                        edgecolor=TEAM_COLOR[team], lw=0.8, ls="--"))
                ax.text(s.x, s.y, f"R{n}", fontsize=6, ha="center", va="center", color=TEAM_COLOR[team])
        for name in layout:
            _draw_station(ax, profile, layout, name, Polygon, FancyArrow)
        ax.set_xlim(f.x_min - 0.4, f.x_max + 0.4)
        ys = [r.y_min for r in profile.insertion.values()] + [f.y_min]
        ax.set_ylim(min(ys) - 0.4, f.y_max + 0.4)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        swapped = ", ".join(layout.swapped) or "none"
        ax.set_title(title or f"{profile.name}, seed {layout.seed}: swapped {swapped}")
        fig.tight_layout()
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path


def _draw_station(ax, profile: Profile, layout: FieldLayout, name: str, Polygon, FancyArrow) -> None:
    pl = layout[name]
    pose = pl.pose
    color = TEAM_COLOR[machine_team(name)]
    box = footprint(profile, pose)
    ax.add_patch(Polygon(box.corners(), closed=True, facecolor=color, edgecolor="black", lw=0.8, alpha=0.85))
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    half = profile.mps.depth / 2.0
    ax.add_patch(FancyArrow(pose.x - c * half * 0.8, pose.y - s * half * 0.8, c * half * 1.4, s * half * 1.4,
                            width=0.03, head_width=0.12, head_length=0.1, color="black",
                            length_includes_head=True))
    tag_in, tag_out = profile.tag_ids(name)
    for sign, label in ((1.0, f"I {tag_in}"), (-1.0, f"O {tag_out}")):
        d = half + 0.22
        ax.text(pose.x + sign * c * d, pose.y + sign * s * d, label, fontsize=6, ha="center",
                va="center", color="black",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": color, "lw": 0.6})
    ax.text(pose.x - s * 0.55, pose.y + c * 0.55, f"{name}\n{pl.rotation_deg}°", fontsize=7,
            ha="center", va="center", weight="bold")
