"""Manual check: a REAL refbox's game clock follows the world's SimTimeSync.

    python benchmarks/refbox_timesync.py --refbox /path/to/rcll-refbox/bin/refbox [--rate 3]

Starts the refbox with simulation time sync on (``--cfg-custom``: simulation
enable, speedup 1, time-sync enable, estimate-time off), then steps a world at
``--rate`` world seconds per wall second, sending SimTimeSync every 0.1 world
s over TCP 4444 (the same link carries SetTeamName/Phase/State), runs SETUP,
pauses the world for a while, and prints the refbox's GameState game_time
beside the world's time.  Exits 0 when, between two GameStates outside the
pause, the refbox's game time advanced as the world's did (within 0.5 s).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

CFG = """%YAML 1.2
%TAG ! tag:fawkesrobotics.org,cfg/
---
# rll-bt time-sync check
---
llsfrb:
  simulation:
    enable: true
    speedup: 1.0
    time-sync:
      enable: true
      estimate-time: false
"""


def comm_cfg(offset: int) -> str:
    """``llsfrb/comm`` keys moving every refbox port by ``offset`` (0: the defaults), so a
    check can run beside another refbox on the same machine."""
    if not offset:
        return ""
    text = f"  comm:\n    server-port: !tcp-port {4444 + offset}\n"
    for peer, send, recv in (("public", 4444, 4445), ("cyan", 4441, 4446), ("magenta", 4442, 4447)):
        text += (f"    {peer}-peer: {{host: !ipv4 127.0.0.1, send-port: !udp-port {send + offset}, "
                 f"recv-port: !udp-port {recv + offset}}}\n")
    return text


def main_cfg_args(refbox: str, run_dir: str, offset: int) -> list[str]:
    """``--cfg-main FILE`` moving the websocket port by ``offset`` (the refbox takes
    that port from its main config only, not from --cfg-custom)."""
    if not offset:
        return []
    src = os.path.join(os.path.dirname(os.path.realpath(refbox)), "..", "cfg", "main", "default_main.yaml")
    with open(src) as f:
        text = f.read()
    dst = os.path.join(run_dir, "main.yaml")
    with open(dst, "w") as f:
        f.write(text.replace("port: 1234", f"port: {1234 + offset}"))
    return ["--cfg-main", dst]


def port_free(port: int) -> bool:
    import socket
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refbox", required=True, help="path of the refbox binary (bin/refbox)")
    ap.add_argument("--rate", type=float, default=3.0, help="world seconds per wall second (default 3)")
    ap.add_argument("--seconds", type=float, default=60.0,
                    help="world seconds to run after the field is generated (default 60)")
    ap.add_argument("--port-offset", type=int, default=0,
                    help="move every refbox port by N (TCP 4444+N ...), to run beside another refbox")
    args = ap.parse_args(argv)
    from backends.sim import World
    from backends.sim.mps.timesync import TimeSync

    run_dir = tempfile.mkdtemp(prefix="rll-bt-timesync-check-")
    cfg = os.path.join(run_dir, "timesync.yaml")
    if not port_free(4444 + args.port_offset):
        print(f"TCP {4444 + args.port_offset} is taken (another refbox?): use --port-offset", file=sys.stderr)
        return 3
    with open(cfg, "w") as f:
        f.write(CFG.replace("llsfrb:\n", "llsfrb:\n" + comm_cfg(args.port_offset), 1))
    out = open(os.path.join(run_dir, "refbox.out"), "w")  # noqa: SIM115 (closed below)
    command = [args.refbox, *main_cfg_args(args.refbox, run_dir, args.port_offset), "--cfg-custom", cfg]
    refbox = subprocess.Popen(command, cwd=run_dir, stdout=out,
                              stderr=subprocess.STDOUT)
    world = World("rcll2025", seed=0)
    sync = TimeSync(port=4444 + args.port_offset, period=0.1)
    rows, ok = [], True
    try:
        if not sync.wait_connected(30):
            print("refbox TCP 4444 not reachable", file=sys.stderr)
            return 3
        ms = sync.ms
        w0 = world.time
        next_wall = time.monotonic()
        started = pause_wall = None
        generated = False
        game_time = None
        gen_time = None
        wall_deadline = time.monotonic() + 300 + args.seconds / args.rate
        while gen_time is None or world.time - gen_time < args.seconds:
            if time.monotonic() > wall_deadline:
                print("the refbox did not generate its field in time", file=sys.stderr)
                break
            wt = world.time - w0
            if pause_wall is None and game_time and game_time >= 6.0:
                pause_wall = time.monotonic()              # the world stands still for 3 wall s
            paused = pause_wall is not None and time.monotonic() - pause_wall < 3.0
            if started is None and wt >= 1.0:
                for m in (ms.SetTeamName(team_name="Carologistics", team_color="CYAN"),
                          ms.SetGamePhase(phase="SETUP"), ms.SetGameState(state="RUNNING")):
                    sync.link.send(m)
                    sync.link.wait(0.2)
                started = wt
            sync.update(world.time, paused=paused)
            for r in sync.link.receive():
                if type(r.msg).__name__ == "GameState" and r.msg.state == ms.enum("GameState.State").Value("RUNNING"):
                    game_time = r.msg.game_time.sec + r.msg.game_time.nsec * 1e-9
            if started is not None and game_time is not None and (
                    not rows or time.monotonic() - rows[-1][0] >= 1.0) and game_time is not None:
                rows.append((time.monotonic(), wt, wt - started, game_time, paused or not generated))
            if not generated and started is not None:
                with open(os.path.join(run_dir, "refbox.out"), errors="replace") as f:
                    generated = "the machine generation is finished" in f.read()
                gen_time = world.time if generated else None
            if paused:
                next_wall = time.monotonic() + 0.02
                time.sleep(0.02)
                sync.link.wait(0.0)
                continue
            # the refbox times its field generation out in game time: the world runs at
            # real time until the field is generated, or the refbox resets the game
            rate = args.rate if generated else 1.0
            next_wall += 0.02 / rate
            ahead = next_wall - time.monotonic()
            if ahead > 0:
                time.sleep(ahead)
            world.step(0.02)
            sync.link.wait(0.0)
    finally:
        sync.close()
        refbox.terminate()
        try:
            refbox.wait(10)
        except subprocess.TimeoutExpired:
            refbox.kill()
        out.close()
        world.close()
    print(f"{'world s':>8} {'refbox game_time':>17} {'d world':>8} {'d refbox':>9}  note")
    prev = None
    for _, wt, _since, gt, p in rows:
        if prev is None:
            print(f"{wt:8.1f} {gt:17.1f}")
        else:
            dw, dg = wt - prev[0], gt - prev[1]
            if not p and not prev[2]:
                ok = ok and abs(dg - dw) < 0.5
            print(f"{wt:8.1f} {gt:17.1f} {dw:8.1f} {dg:9.1f}  {'paused or generating field (rate 1)' if p else ''}")
        prev = (wt, gt, p)
    print(f"rate {args.rate} world s per wall s; logs in {run_dir}; "
          f"{'every' if ok else 'NOT every'} interval outside a pause followed the world within 0.5 s")
    return 0 if rows and ok else 1


if __name__ == "__main__":
    sys.exit(main())
