"""UDP broadcast peer, as protobuf_comm's ProtobufBroadcastPeer.

Binds ``0.0.0.0:recv_port`` with SO_BROADCAST and SO_REUSEADDR, sends from
the same socket to ``host:send_port`` (single-port mode: ``recv_port ==
send_port``), and drops datagrams that come from one of its own local IPs
*and* its own port (its own broadcasts coming back).  Datagrams over 1024
bytes are refused on send and dropped on receipt.  With a key the peer sends
encrypted frames and drops plain ones; without, the reverse.
"""
from __future__ import annotations

import fcntl
import ipaddress
import logging
import os
import select
import socket
import struct
from collections.abc import Callable

from ..clock import Clock
from . import stats as S
from .codec import FrameCodec
from .crypto import TEAM_CIPHER
from .framing import FRAME_V2, MAX_DATAGRAM
from .registry import MessageRegistry
from .transport import CryptoSwitch, PumpedTransport, Received

log = logging.getLogger("rll_bt.comm")

_RECV_BUFSIZE = 65536
_MAX_PER_PUMP = 10000


def local_ipv4_addresses(probe_host: str | None = None) -> set[str]:
    """IPv4 addresses of this host's interfaces (best effort, Linux ioctl + resolver),
    plus the source address used to reach ``probe_host``."""
    ips = {"0.0.0.0", "127.0.0.1"}
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            ips.add(info[4][0])
    except OSError:
        pass
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for _idx, name in socket.if_nameindex():
                try:
                    req = struct.pack("256s", name.encode()[:15])
                    res = fcntl.ioctl(s.fileno(), 0x8915, req)  # SIOCGIFADDR
                    ips.add(socket.inet_ntoa(res[20:24]))
                except OSError:
                    continue
    except (OSError, AttributeError):
        pass
    if probe_host:
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
                s.connect((probe_host, 9))
                ips.add(s.getsockname()[0])
        except OSError:
            pass
    return ips


class UdpPeer(CryptoSwitch, PumpedTransport):
    """A broadcast peer on one channel.

    ``host``: where to send (a broadcast address, or 127.0.0.1 locally).
    ``send_port``/``recv_port``: ``recv_port`` None means single-port mode
    (``recv_port = send_port``); 0 binds an ephemeral port (see :attr:`recv_port`).
    ``registry``: message classes accepted on receipt.
    ``channel``: name put into each :class:`Received` ("public", "team", ...).
    ``key``/``cipher``: team key and cipher id (2 = AES-128-CBC) for an
    encrypted channel; :meth:`set_crypto` switches it on later.
    ``clock``: stamps :attr:`Received.time` (default wall clock).
    """

    def __init__(self, host: str, send_port: int, recv_port: int | None = None, *,
                 registry: MessageRegistry, channel: str = "public",
                 key: str | bytes | None = None, cipher: int | str = TEAM_CIPHER,
                 bind_host: str = "0.0.0.0", clock: Clock | None = None,
                 frame_version: int = FRAME_V2, max_datagram: int = MAX_DATAGRAM,
                 iv_source: Callable[[int], bytes] = os.urandom):
        super().__init__(channel, clock)
        self.host = host
        self.send_port = int(send_port)
        recv_port = self.send_port if recv_port is None else int(recv_port)
        self.stats = S.DropStats(f"{channel} udp recv :{recv_port}")
        self.codec = FrameCodec(registry, key=key, cipher=cipher, frame_version=frame_version,
                                max_frame=max_datagram, stats=self.stats, iv_source=iv_source)
        self.max_datagram = max_datagram
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            try:  # best effort: more room between polls (the kernel caps it at rmem_max)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
            except OSError:
                pass
            sock.bind((bind_host, recv_port))
            sock.setblocking(False)
        except OSError:
            sock.close()
            raise
        self._sock = sock
        self.recv_port = sock.getsockname()[1]
        self.stats.name = f"{channel} udp recv :{self.recv_port}"
        self._own_ips = local_ipv4_addresses(host)
        self._send_errors: set[int] = set()

    # -- send ----------------------------------------------------------------
    def send(self, msg) -> bool:
        """Encode and send ``msg`` to ``host:send_port``.  Raises
        :class:`~rll_bt.comm.errors.FrameTooLarge` over 1024 B; returns False
        (logged once per errno) if the OS refuses the datagram."""
        frame = self.codec.encode(msg)
        return self.send_frame(frame)

    def send_frame(self, frame: bytes) -> bool:
        """Send already-encoded bytes (used by tests and relays)."""
        try:
            self._sock.sendto(frame, (self.host, self.send_port))
            return True
        except OSError as exc:
            code = exc.errno or -1
            if code not in self._send_errors:
                self._send_errors.add(code)
                log.warning("%s: cannot send to %s:%d: %s", self.channel, self.host,
                            self.send_port, exc)
            return False

    # -- receive -------------------------------------------------------------
    def is_own(self, addr: tuple[str, int]) -> bool:
        """True for a datagram from this host's own address and this peer's port."""
        ip, port = addr[0], addr[1]
        if port != self.recv_port:
            return False
        if ip in self._own_ips:
            return True
        try:
            return ipaddress.ip_address(ip).is_loopback
        except ValueError:
            return False

    def _pump(self) -> None:
        for _ in range(_MAX_PER_PUMP):
            try:
                data, addr = self._sock.recvfrom(_RECV_BUFSIZE)
            except (BlockingIOError, InterruptedError):
                return
            except ConnectionRefusedError:  # a late ICMP for an earlier send
                continue
            except OSError as exc:
                log.debug("%s: recvfrom: %s", self.channel, exc)
                return
            if self.is_own(addr):
                self.stats.own += 1
                continue
            decoded = self.codec.decode(data)
            if decoded is not None:
                self._deliver(Received.of(decoded, self.channel, addr, self.clock.now()))

    def _wait_io(self, timeout: float) -> None:
        try:
            select.select([self._sock], [], [], max(0.0, timeout))
        except (OSError, ValueError):
            pass

    def _close_io(self) -> None:
        self._sock.close()

    def __repr__(self) -> str:
        return (f"UdpPeer({self.channel!r}, send {self.host}:{self.send_port}, "
                f"recv :{self.recv_port}, {'encrypted' if self.encrypted else 'plain'})")
