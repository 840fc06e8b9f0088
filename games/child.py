"""The team server as its own process of a ``rll-bt sim --processes`` game.

    python -m games.child CONFIG.json

``CONFIG.json`` names the rules profile, team and key, the refbox's UDP
ports (robot's view: ``public``/``cyan`` as [send, recv]) and broadcast
host, the TCP port the agents connect to, the state database, the
exploration strategy and seed, and ``snapshot``: a JSON file this process
rewrites every ``snapshot_period`` s with the team server's view (the
handle's ``snapshot()`` plus ``now``, its clock).  It runs on the wall
clock until SIGTERM, then writes a last snapshot and exits 0.
"""
from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path


class _Stop(Exception):
    pass


def write_snapshot(path: Path, snap: dict) -> None:
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(snap, default=str))
    os.replace(tmp, path)


def run(cfg: dict) -> int:
    from rll_bt import msgs
    from rll_bt.agenttask import link as agent_link
    from rll_bt.clock import WallClock
    from rll_bt.comm import MessageRegistry, UdpPeer
    from rll_bt.comm.msglog import MessageLog
    from rll_bt.contracts import TeamServerOptions, load_teamserver

    from .teamlog import LoggedStreamServer

    clock = WallClock()
    ref_reg = MessageRegistry.from_message_set(msgs.message_set(cfg["profile"]))
    team_reg = agent_link.registry()
    host = cfg["refbox_host"]
    ports = cfg["ports"]

    def public():
        send, recv = ports["public"]
        return UdpPeer(host, send, recv, registry=ref_reg, channel="public", clock=clock)

    def team(color: str):
        send, recv = ports[color.lower()]
        return UdpPeer(host, send, recv, registry=ref_reg, channel="team", clock=clock)

    msglog = None
    if cfg.get("message_log"):
        msglog = MessageLog(cfg["message_log"], clock, {}, team_reg, line_buffered=True)

    def agents():
        kw = {"key": cfg["key"], "host": "127.0.0.1", "clock": clock}
        if msglog is None:
            return agent_link.tcp_server(cfg["listen"], **kw)
        channel = cfg.get("log_channel", "teamserver")
        return agent_link.tcp_server(cfg["listen"], cls=LoggedStreamServer, log=msglog, channel=channel, server=channel,
                                  prefix=cfg.get("robot_prefix", ""), **kw)

    oracle = cfg.get("oracle")
    handle = load_teamserver(cfg.get("teamserver", "htn"))(
        profile=cfg["profile"], team_name=cfg["team"], key=cfg["key"], clock=clock, refbox_public=public,
        refbox_team=team, agents=agents, state=cfg["state"], strategy=cfg["strategy"], seed=cfg["seed"],
        oracle={k: int(v) for k, v in oracle.items()} if oracle else None,
        options=TeamServerOptions(baseline=cfg.get("baseline", False), map_period=cfg.get("map_period", 5.0),
                                  extra=cfg.get("extra") or {}))
    snapshot = Path(cfg["snapshot"])
    period = float(cfg.get("snapshot_period", 1.0))

    def on_term(signum, frame):
        raise _Stop()
    signal.signal(signal.SIGTERM, on_term)
    next_snap = clock.now()
    try:
        while True:
            handle.tick()
            now = clock.now()
            if now >= next_snap:
                next_snap = now + period
                write_snapshot(snapshot, {**handle.snapshot(), "now": now})
            clock.sleep(0.01)
    except (_Stop, KeyboardInterrupt):
        pass
    finally:
        try:
            write_snapshot(snapshot, {**handle.snapshot(), "now": clock.now()})
        finally:
            handle.close()
            if msglog is not None:
                msglog.close()
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m games.child CONFIG.json", file=sys.stderr)
        return 2
    return run(json.loads(Path(argv[0]).read_text()))


if __name__ == "__main__":
    sys.exit(main())
