"""A free port offset for a refbox started on its ports moved by ``--refbox-port-offset``."""
from __future__ import annotations

import os
import random
import socket
import time

REFBOX_UDP = range(4441, 4448)


def free_port_offset(udp=REFBOX_UDP, tcp=(), host: str = "127.0.0.1", tries: int = 200) -> int:
    """An offset N whose ports ``udp`` + N (UDP) and ``tcp`` + N (TCP) are all free on ``host`` now
    (random, so parallel test workers rarely pick the same); RuntimeError when none is found."""
    rng = random.Random(os.getpid() ^ time.monotonic_ns())
    for _ in range(tries):
        off = rng.randrange(15000, 60000)
        socks = []
        try:
            for kind, ports in ((socket.SOCK_DGRAM, udp), (socket.SOCK_STREAM, tcp)):
                for port in ports:
                    s = socket.socket(socket.AF_INET, kind)
                    socks.append(s)
                    s.bind((host, port + off))
            return off
        except OSError:
            continue
        finally:
            for s in socks:
                s.close()
    raise RuntimeError(f"no free port offset for {list(udp)} / {list(tcp)} on {host}")
