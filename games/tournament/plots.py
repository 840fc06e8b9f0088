"""``scores.png``: each configuration's score distribution over its games.

One box per configuration (median, quartiles, whiskers at 1.5 IQR) with
every game's score drawn over it as a dot, cyan games and magenta games in
their colours, so a strategy that only wins one side of the field shows.
"""
from __future__ import annotations

from pathlib import Path

from ..plots import TEAM_COLOR, _plt


def draw_scores(configs: list[str], rows, path: str | Path) -> Path:
    plt = _plt()
    played = [r for r in rows if not r.get("error")]
    fig, ax = plt.subplots(figsize=(max(4.0, 1.8 * len(configs) + 1.5), 4.2))
    try:
        data = []
        for c in configs:
            data.append([r["points"][color] for r in played for color in ("cyan", "magenta") if r[color] == c])
        ax.boxplot([d or [0] for d in data], widths=0.5, showfliers=False)
        ax.set_xticks(range(1, len(configs) + 1), configs, fontsize=8)
        for i, c in enumerate(configs, start=1):
            for k, color in enumerate(("cyan", "magenta")):
                pts = [r["points"][color] for r in played if r[color] == c]
                xs = [i - 0.12 + 0.24 * k] * len(pts)
                ax.scatter(xs, pts, s=14, color=TEAM_COLOR[color.upper()], alpha=0.8, zorder=3,
                           label=f"as {color}" if i == 1 else None)
        ax.set_ylabel("points per game")
        ax.grid(axis="y", alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
        n = len(played)
        ax.set_title(f"score distribution over {n} game{'s' if n != 1 else ''}", fontsize=9)
        fig.tight_layout()
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)
    return Path(path)
