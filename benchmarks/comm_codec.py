"""Throughput of rll_bt.comm: frame encode/decode per cipher, the bus, and UDP on loopback.

Run: .venv/bin/python benchmarks/comm_codec.py [--n 20000]
Prints a table of frames per second (wall clock) for a GameState and a
MachineInfo with 12 machines from the rcll2016 set.
"""
from __future__ import annotations

import argparse
import time

from rll_bt import msgs
from rll_bt.comm import Bus, FrameCodec, MessageRegistry, UdpPeer


def sample_messages(ms):
    gs = ms.GameState(state=ms.GameState.RUNNING, phase=ms.GameState.PRODUCTION,
                      team_cyan="Carologistics", team_magenta="GRIPS", points_cyan=42)
    gs.game_time.sec, gs.game_time.nsec = 123, 0
    mi = ms.MachineInfo(team_color=0)
    for i in range(12):
        m = mi.machines.add(name=f"C-M{i}", type="RS", state="IDLE", zone=1 + i)
        m.lights.add(color=0, state=1)
    return {"GameState": gs, "MachineInfo x12": mi}


def rate(fn, n):
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20000, help="frames per measurement")
    n = ap.parse_args().n
    ms = msgs.message_set("rcll2016")
    reg = MessageRegistry.from_message_set(ms)
    rows = []
    for label, msg in sample_messages(ms).items():
        for cname, key, cipher in (("plain", None, 2), ("aes-128-cbc", "k", 2),
                                   ("aes-256-ecb", "k", 3)):
            codec = FrameCodec(reg, key=key, cipher=cipher)
            frame = codec.encode(msg)
            rows.append((label, cname, len(frame), rate(lambda: codec.encode(msg), n),
                         rate(lambda: codec.decode(frame), n)))
    print(f"{'message':<16} {'cipher':<12} {'bytes':>6} {'encode/s':>10} {'decode/s':>10}")
    for label, cname, size, enc, dec in rows:
        print(f"{label:<16} {cname:<12} {size:>6} {enc:>10.0f} {dec:>10.0f}")

    gs = sample_messages(ms)["GameState"]
    bus = Bus()
    tx = bus.peer("cyan", registry=reg, key="k")
    rxs = [bus.peer("cyan", registry=reg, key="k") for _ in range(5)]
    t0 = time.perf_counter()
    for _ in range(n // 10):
        tx.send(gs)
        for r in rxs:
            r.receive()
    bus_rate = (n // 10) / (time.perf_counter() - t0)

    a = UdpPeer("127.0.0.1", 0, 0, registry=reg)
    b = UdpPeer("127.0.0.1", a.recv_port, 0, registry=reg)
    a.send_port = b.recv_port
    got, t0 = 0, time.perf_counter()
    for i in range(n // 10):
        a.send(gs)
        if i % 50 == 49:
            got += len(b.receive())
    deadline = time.perf_counter() + 2
    while got < n // 10 and time.perf_counter() < deadline:
        b.wait(0.01)
        got += len(b.receive())
    udp_rate = got / (time.perf_counter() - t0)
    a.close()
    b.close()
    print(f"\n{'transport':<40} {'msgs/s':>10}")
    print(f"{'bus, encrypted, 1 sender -> 5 receivers':<40} {bus_rate:>10.0f}")
    print(f"{'udp loopback, plain (received)':<40} {udp_rate:>10.0f}  ({got}/{n // 10} arrived)")


if __name__ == "__main__":
    main()
