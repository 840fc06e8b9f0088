"""Watching one process of a team on the wall clock: ``rll-bt agent`` and
``rll-bt teamserver`` with ``--record FILE.mcap`` and ``--live [PORT]``.

    watch = wall_watch(record="r1.mcap", live=None, name="rll-bt agent", meta={"kind": "agent", "robot": 1})
    robot, backend, link, public, team = watch_agent(watch, 1, backend, link, public, team)
    agent = RobotAgent(..., backend=backend, link=link, public=public, team=team)
    robot.attach(agent)

Message times are Unix time (``base_ns`` is the Unix time of the
monotonic clock's zero, written in the ``rll-bt`` metadata with ``clock:
wall``), so recordings of several processes of one machine line up:
:func:`games.merge` puts those of a ``rll-bt sim --processes`` game on
the game's clock.
"""
from __future__ import annotations

import time
from pathlib import Path

from ..clock import WallClock
from .links import LINK, LinkRecorder
from .robot import RobotWatch
from .sink import Watch

#: a process that may be killed (SIGKILL) loses at most this much of its recording
CHUNK = 64 * 1024


def wall_watch(*, record: str | Path | None, live: int | None, name: str, meta: dict | None = None,
               host: str = "127.0.0.1") -> Watch:
    """A :class:`Watch` on the machine's monotonic clock, stamped in Unix time."""
    base_ns = time.time_ns() - time.monotonic_ns()
    return Watch(record=record, live=live, clock=WallClock(), name=name, base_ns=base_ns,
                 meta={"clock": "wall", **(meta or {})}, host=host, chunk_size=CHUNK)


def watch_links(watch: Watch, me: str, *, link=None, public=None, team=None):
    """``(link, public, team)`` watched as ``me`` sees them (:mod:`.links`): the
    team-server link, the refbox's public channel and a team-channel factory
    (colour -> transport); a part given as None stays None."""
    links = LinkRecorder(watch, me)
    return (None if link is None else links.wrap(link, LINK),
            None if public is None else links.wrap(public, "public"),
            None if team is None else links.wrap_team(team))


def watch_agent(watch: Watch, number: int, backend, link, public, team, *, camera_hz: float = 0.0):
    """Robot ``number``'s parts watched: ``(robot_watch, backend, link, public, team)``;
    attach the agent made of them with ``robot_watch.attach(agent)``."""
    robot = RobotWatch(watch, number, force_camera_hz=camera_hz)
    return (robot, robot.tap(backend), *watch_links(watch, f"robot{number}", link=link, public=public, team=team))


__all__ = ["wall_watch", "watch_agent", "watch_links"]
