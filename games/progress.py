"""A one-line progress bar on stderr: simulated time, phase, game time, score.

On a terminal the line is redrawn in place (at most ``every`` wall seconds);
elsewhere (a log, CI) a plain line is printed every ``every_plain`` wall
seconds, so a long run still shows it is alive.
"""
from __future__ import annotations

import sys
from typing import IO

from rll_bt.clock import Clock, WallClock


class ProgressBar:
    def __init__(self, total: float, *, stream: IO[str] | None = None, clock: Clock | None = None,
                 team: str | tuple[str, ...] = "CYAN", width: int = 28, every: float = 0.25,
                 every_plain: float = 15.0):
        self.total = max(float(total), 1e-9)
        self.stream = stream or sys.stderr
        self.clock = clock or WallClock()
        self.team = team
        self.width = width
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.every = every if self.tty else every_plain
        self.t0 = self.clock.now()
        self._last = -1e9
        self._drawn = False

    def line(self, sim_t: float, status) -> str:
        frac = min(max(sim_t / self.total, 0.0), 1.0)
        fill = int(round(frac * self.width))
        wall = self.clock.now() - self.t0
        speed = sim_t / wall if wall > 0 else 0.0
        return (f"[{'#' * fill}{'.' * (self.width - fill)}] {sim_t:6.0f}/{self.total:.0f} s  "
                f"{status.phase:<11} {status.game_time:5.0f} s  score {self._score(status)}  "
                f"wall {wall:5.0f} s ({speed:4.1f}x)")

    def _score(self, status) -> str:
        """Our points, or both teams' ("C 12 : M 8") when ``team`` names two."""
        if isinstance(self.team, str):
            return f"{status.points.get(self.team, 0):4d}"
        return " : ".join(f"{t[0]} {status.points.get(t, 0)}" for t in self.team)

    def __call__(self, sim_t: float, status) -> None:
        now = self.clock.now()
        if now - self._last < self.every:
            return
        self._last = now
        text = self.line(sim_t, status)
        if self.tty:
            self.stream.write("\r" + text)
            self._drawn = True
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def done(self, sim_t: float, status) -> None:
        text = self.line(sim_t, status)
        self.stream.write(("\r" + text + "\n") if self.tty else text + "\n")
        self.stream.flush()
