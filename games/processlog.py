"""What the processes of a ``--processes`` game logged, named and timed as lockstep's.

- :func:`udp_sender`: who sent a message the refbox process logged;
- :func:`shift_recording`: a recording made on the world's clock, moved to
  the game's start (the world runs while the processes come up);
- :func:`game_logs`: each team's task runs read from its team server's
  message logs (a run cut off where its agent was killed), and those logs
  merged with the refbox processes' into the game's ``messages.jsonl``.
"""
from __future__ import annotations

from pathlib import Path

from .teamlog import merge_into, read_lines, task_runs

__all__ = ["game_logs", "shift_recording", "udp_sender"]


def shift_recording(rec, t0: float) -> None:
    """Every time of the recording ``rec`` made ``t0`` seconds earlier (in place)."""
    def s(t):
        return None if t is None else round(t - t0, 3)
    rec.samples = [{**x, "t": s(x["t"])} for x in rec.samples]
    rec.paths = {n: [(s(t), x, y) for t, x, y in pts] for n, pts in rec.paths.items()}
    rec.stations = {n: [(s(t), st) for t, st in hist] for n, hist in rec.stations.items()}
    rec.phases = [(s(t), p) for t, p in rec.phases]
    rec.events = [{**e, "t": s(e["t"])} for e in rec.events]
    rec.tasks = {n: [{**r, "start": s(r["start"]), "end": s(r["end"])} for r in runs]
                 for n, runs in rec.tasks.items()}
    rec.known_all_at = s(rec.known_all_at)
    rec.exploration_started = s(rec.exploration_started)


def udp_sender(entry: dict, servers: dict[str, str] | None = None) -> str:
    """Who sent a message the refbox logged, named as lockstep names them.

    On loopback every robot and the team server send from the same address
    (each binds the shared receive port), so the address tells nobody
    apart: a beacon names its robot (``peer_name``, else ``R<number>``), and
    everything else reaching the refbox here comes from the team server
    (reports, machine instructions): of the channel's team with ``servers``
    (channel -> name, two teams).  The refbox's own sends keep "refbox"."""
    if entry["from"] == "refbox":
        return "refbox"
    if entry.get("type") == "BeaconSignal":
        msg = entry.get("msg") or {}
        return msg.get("peer_name") or f"R{msg.get('number', 0)}"
    if servers:
        return servers.get(entry.get("channel", ""), "teamserver")
    return "teamserver"



def game_logs(folder: Path, refbox_logs: list[Path], team_logs: dict[str, list[Path]], time_map, *, t0: float,
              end: float, recordings: dict, channels: dict[str, str], kills: list[tuple[float, str, int]],
              servers: dict[str, str] | None) -> int:
    """Every team's task runs (``recordings[colour].tasks``) from its team server's
    message logs (``team_logs``, one per process start, on the wall clock that
    ``time_map`` maps onto the simulation's), a run under way when its agent was
    killed (``kills``: (time, colour, robot)) ending then; every recording moved
    to the game's start ``t0``.  Without refbox logs (a game neither saved nor
    recorded) that is all.  Else the refbox processes' logs (one per process: a
    restarted refbox writes a new one) and the team servers' are merged in time
    order into ``folder/messages.jsonl`` and removed; returns the messages it holds."""
    team = sorted((e for logs in team_logs.values() for path in logs for e in read_lines(path, time_map)),
                  key=lambda e: e["t"])
    for color, rec in recordings.items():
        if color not in channels:
            continue                   # an external team: no log of ours
        rec.tasks = task_runs(team, end=end, channel=channels[color], server=channels[color])
        for t, c, robot in kills:
            for run in rec.tasks.get(robot, []) if c == color else ():
                if run["start"] <= t < run["end"]:
                    run["end"], run["outcome"] = t, "agent killed"
    for rec in recordings.values():
        shift_recording(rec, t0)
    if not refbox_logs:
        return 0
    refbox = sorted(({**e, "from": udp_sender(e, servers)} for path in refbox_logs
                     for e in read_lines(path, time_map)), key=lambda e: e["t"])
    messages = merge_into(folder / "messages.jsonl", refbox, team, shift=t0)
    for path in [*refbox_logs, *(p for logs in team_logs.values() for p in logs)]:
        path.unlink(missing_ok=True)
    return messages
