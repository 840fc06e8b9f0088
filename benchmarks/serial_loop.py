"""Robotino serial loop against the emulator: poll rate, jitter, watchdog trips.

Run: .venv/bin/python benchmarks/serial_loop.py [--seconds 60] [--cycle-ms 5]
     [--corrupt P] [--drop P] [--delay MS] [--in-process]

Starts ``rll-bt robotino emulate`` in its own process (or in this one with
``--in-process``), opens the robotino backend on its pty and drives a
slowly varying velocity for the given time, refreshing the command every
50 ms.  Prints a table: polls sent per second, cycle period p50/p95/p99/max,
replies per poll, checksum errors on both sides, reopens, and the base's
communication-watchdog trips while the motors were turning (must be 0).
"""
from __future__ import annotations

import argparse
import json
import math
import signal
import subprocess
import sys
import time

import numpy as np

from backends.robotino.backend import RobotinoBackend


def start_emulator(args):
    """(device, finish) where finish() -> emulator stats dict."""
    fault_args = ["--corrupt", str(args.corrupt), "--drop", str(args.drop), "--delay", str(args.delay),
                  "--seed", "1"]
    if args.in_process:
        from backends.robotino.emulator import RobotinoEmulator
        from backends.robotino.faults import Faults
        emu = RobotinoEmulator(faults=Faults(args.corrupt, args.drop, args.delay, seed=1)).start()

        def finish():
            stats = emu.stats()
            emu.stop()
            return stats
        return emu.device, finish
    cmd = [sys.executable, "-c", "import sys; from rll_bt.cli import main; sys.exit(main())",
           "robotino", "emulate", "--report", "0", *fault_args]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    device = proc.stdout.readline().strip()        # the base's path comes first
    if not device:
        proc.kill()
        raise SystemExit("the emulator did not start")

    def finish():
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:     # its counts are lost, the host's are not
            proc.send_signal(signal.SIGUSR1)   # its stacks to stderr: where it hangs
            time.sleep(1.0)
            proc.kill()
            out, _ = proc.communicate()
            print("the emulator did not exit within 30 s of SIGINT: killed, its counts are unknown",
                  file=sys.stderr)
        for line in out.splitlines():
            if line.startswith("summary: "):
                return json.loads(line[len("summary: "):])
        return {}
    return device, finish


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="how long to drive (default 60)")
    ap.add_argument("--cycle-ms", type=float, default=5.0, help="poll cycle, 5..10 ms (default 5)")
    ap.add_argument("--corrupt", type=float, default=0.0, help="per-byte corruption probability")
    ap.add_argument("--drop", type=float, default=0.0, help="per-byte drop probability")
    ap.add_argument("--delay", type=float, default=0.0, help="reply delay in ms")
    ap.add_argument("--in-process", action="store_true", help="run the emulator in this process")
    args = ap.parse_args()
    if args.seconds <= 0 or not 5.0 <= args.cycle_ms <= 10.0:
        ap.error("--seconds must be > 0 and --cycle-ms within 5..10")

    device, finish = start_emulator(args)
    robot = RobotinoBackend(device, cycle_time=args.cycle_ms / 1000.0, handshake_timeout=2.0)
    start = time.monotonic()
    next_report = start + 5.0
    try:
        while (t := time.monotonic() - start) < args.seconds:
            robot.drive(0.3 * math.sin(0.5 * t), 0.1 * math.cos(0.3 * t), 0.6 * math.sin(0.2 * t))
            if time.monotonic() >= next_report:
                next_report += 5.0
                s = robot.link_stats()
                print(f"  {t:5.1f} s  polls {s.polls}  frames {s.frames}  "
                      f"checksum errors {s.checksum_errors}", file=sys.stderr, flush=True)
            time.sleep(0.05)
        elapsed = time.monotonic() - start
        stats = robot.link_stats()
        periods = np.asarray(robot.base.cycle_periods()) * 1000.0
    finally:
        robot.close()
        emu_stats = finish()

    p50, p95, p99 = np.percentile(periods, [50, 95, 99]) if len(periods) else (math.nan,) * 3
    rows = [
        ("duration", f"{elapsed:.1f} s"),
        ("nominal cycle", f"{args.cycle_ms:.1f} ms ({1000.0 / args.cycle_ms:.0f} Hz)"),
        ("polls sent", f"{stats.polls} ({stats.polls / elapsed:.1f} /s)"),
        ("cycle period p50", f"{p50:.2f} ms"),
        ("cycle period p95", f"{p95:.2f} ms"),
        ("cycle period p99", f"{p99:.2f} ms"),
        ("cycle period max", f"{periods.max() if len(periods) else math.nan:.2f} ms"),
        ("replies per poll", f"{stats.frames / max(1, stats.polls):.3f}"),
        ("host checksum/framing errors", f"{stats.checksum_errors} / {stats.framing_errors}"),
        ("base checksum errors", str(emu_stats.get("checksum_errors", "?"))),
        ("read timeouts / link losses", f"{stats.read_timeouts} / {stats.link_losses}"),
        ("watchdog trips (all)", str(emu_stats.get("watchdog_trips", "?"))),
        ("watchdog stops while moving", str(emu_stats.get("watchdog_motion_stops", "?"))),
        ("emulator", "in-process" if args.in_process else "own process"),
    ]
    width = max(len(k) for k, _ in rows)
    print(f"{'metric':<{width}}  value")
    print(f"{'-' * width}  {'-' * 24}")
    for key, value in rows:
        print(f"{key:<{width}}  {value}")


if __name__ == "__main__":
    main()
