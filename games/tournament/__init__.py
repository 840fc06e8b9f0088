"""Tournaments: a round robin of team configurations over many seeded games.

    from games.tournament import run_tournament
    out = run_tournament(["htn", "baseline"], seeds=[1, 2, 3], out=Path("t"), jobs=2)
    print(out["table"])

- :mod:`.schedule`: the games (every pair, both colours, every seed);
- :mod:`.play`: one game as a worker plays it (plain data in and out);
- :mod:`.executors`: a local process pool or a Dask cluster runs them;
- :mod:`.store`: the rows kept in ``tournament.sqlite`` (a killed
  tournament resumes where it stopped);
- :mod:`.table`, :mod:`.plots`: the table, ``games.csv``, ``scores.png``;
- :mod:`.cli`: ``rll-bt tournament``.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

from .schedule import Match, normalise, round_robin, settings

__all__ = ["Match", "run_tournament", "settings", "round_robin", "Progress"]


class Progress:
    """Games done of all, the last game's score, elapsed and left (wall) on one line of stderr."""

    def __init__(self, total: int, done: int = 0, stream=None, width: int = 24):
        self.total, self.done, self.width = total, done, width
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.monotonic()
        self.start_done = done

    def line(self, last: str = "") -> str:
        frac = self.done / self.total if self.total else 1.0
        fill = int(round(frac * self.width))
        el = time.monotonic() - self.t0
        new = self.done - self.start_done
        left = el / new * (self.total - self.done) if new else None
        eta = f"  left ~{_dur(left)}" if left is not None and self.done < self.total else ""
        return (f"[{'#' * fill}{'.' * (self.width - fill)}] {self.done}/{self.total} games  "
                f"{_dur(el)}{eta}" + (f"  {last}" if last else ""))

    def show(self, last: str = "") -> None:
        text = self.line(last)
        self.stream.write(("\r" + text + "\x1b[K") if self.tty else text + "\n")
        self.stream.flush()

    def game(self, row: dict) -> None:
        self.done += 1
        if row.get("error"):
            last = f"seed {row['seed']} {row['cyan']} : {row['magenta']} failed"
        else:
            p = row["points"]
            last = f"seed {row['seed']} {row['cyan']} {p['cyan']} : {p['magenta']} {row['magenta']}"
        self.show(last)

    def close(self) -> None:
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()


def _dur(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.0f} min" if s < 7200 else f"{s / 3600:.1f} h"


def run_tournament(configs: list[str], seeds: list[int], out: str | Path, *, executor: str = "local",
                   jobs: int = 1, address: str | None = None, progress: bool = False,
                   play: Callable[[dict], dict] | None = None, **game) -> dict:
    """Play (or resume) the round robin of ``configs`` on ``seeds`` with the
    game settings ``game`` (:data:`.schedule.SETTINGS`); returns ``rows``
    (every game of it, in schedule order), ``played`` (games played now),
    ``table`` (text), ``standings`` and ``files`` written to ``out``."""
    from .executors import open_executor
    from .play import play_match
    from .store import Store
    from .table import games_csv, games_text, render, standings
    configs = normalise(configs)
    shared = settings(**game)
    matches = round_robin(configs, seeds, shared)
    out = Path(out)
    played = 0
    with Store(out, shared) as store:
        have = store.rows()
        todo = [m for m in matches if m.key not in have or have[m.key].get("error")]
        bar = Progress(len(matches), len(matches) - len(todo)) if progress else None
        if todo:
            if bar is not None:
                bar.show("starting" if len(todo) == len(matches) else "resumed")
            with open_executor(executor, jobs=jobs, address=address) as ex:
                for _i, row in ex.run(play or play_match, [m.to_dict() for m in todo]):
                    store.add(row)
                    played += 1
                    if bar is not None:
                        bar.game(row)
        if bar is not None:
            bar.close()
        have = store.rows()
    rows = [have[m.key] for m in matches if m.key in have]
    (out / "games.csv").write_text(games_csv(rows))
    text = render(configs, rows, planned=len(matches))
    (out / "table.txt").write_text(text + "\n\n" + games_text(rows) + "\n")
    files = ["tournament.sqlite", "games.csv", "table.txt"]
    from .plots import draw_scores
    draw_scores(configs, rows, out / "scores.png")
    files.append("scores.png")
    return {"rows": rows, "played": played, "planned": len(matches), "table": text,
            "standings": standings(configs, rows), "games": games_text(rows), "files": files,
            "failed": [r for r in rows if r.get("error")]}
