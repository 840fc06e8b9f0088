"""What the processes of a ``--processes`` game logged, named and timed as lockstep's.

- :func:`udp_sender`: who sent a message the refbox process logged;
- :func:`shift_recording`: a recording made on the world's clock, moved to
  the game's start (the world runs while the processes come up).
"""
from __future__ import annotations

__all__ = ["shift_recording", "udp_sender"]


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
