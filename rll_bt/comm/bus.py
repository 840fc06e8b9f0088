"""In-process bus for lockstep runs: the same encoded frames, no sockets, no threads.

- :meth:`Bus.peer` joins a named *channel* that acts like UDP broadcast:
  every other endpoint on the channel gets the encoded bytes, and each
  decodes them with its own key (so a wrong key or a missing one drops the
  frame, exactly as on the network).  The 1024-byte datagram limit applies.
- :meth:`Bus.stream_server` / :meth:`Bus.stream_client` act like the TCP
  link: a server at an address, clients that connect to it (and reconnect
  on their next poll once a closed server is back), per-client ids.  With a
  key the link is secured like the TCP link (:mod:`.secure`: hellos, then
  sealed frames); a tap sees each message of a secured link as a plain frame
  (the sealed bytes are per connection, so only the two ends can open them).

Delivery is polled: frames wait in the receiver's inbox until its
``receive()``.  Order is send order, so a seeded run is deterministic.
"""
from __future__ import annotations

import itertools
import os
from collections import deque
from collections.abc import Callable
from typing import Any

from ..clock import Clock
from . import stats as S
from .codec import FrameCodec
from .crypto import TEAM_CIPHER
from .framing import FRAME_HEADER_SIZE, MAX_DATAGRAM, MAX_STREAM_PAYLOAD
from .registry import MessageRegistry
from .secure import CLIENT, LINK_CIPHER, SERVER, stream_crypto
from .transport import CONNECTED, DISCONNECTED, CryptoSwitch, LinkEvent, Received

_STREAM_MAX_FRAME = FRAME_HEADER_SIZE + MAX_STREAM_PAYLOAD

#: a bus stream client's name for its one connection
_SERVER = "server"

#: a tap sees (channel or address, source name, frame bytes)
Tap = Callable[[str, Any, bytes], None]


class Bus:
    """The in-process network.  ``clock`` stamps :attr:`Received.time` (0.0 without one)."""

    def __init__(self, clock: Clock | None = None):
        self.clock = clock
        self._channels: dict[str, list[BusPeer]] = {}
        self._servers: dict[str, BusStreamServer] = {}
        self._ids = itertools.count(1)
        self._taps: list[Tap] = []
        self.frames = 0  #: frames carried so far

    def now(self) -> float:
        return self.clock.now() if self.clock is not None else 0.0

    def tap(self, fn: Tap) -> None:
        """Call ``fn(channel, source, frame)`` for every frame sent (recording, debugging)."""
        self._taps.append(fn)

    def _carry(self, where: str, source: Any, frame: bytes) -> None:
        self.frames += 1
        for fn in self._taps:
            fn(where, source, frame)

    # -- factories ---------------------------------------------------------------
    def peer(self, channel: str, *, registry: MessageRegistry, key: str | bytes | None = None,
             cipher: int | str = TEAM_CIPHER, name: str | None = None,
             label: str | None = None, max_datagram: int = MAX_DATAGRAM,
             iv_source: Callable[[int], bytes] = os.urandom) -> BusPeer:
        """Join broadcast ``channel`` (e.g. "public", "cyan").  ``label`` is the
        :attr:`Received.channel` name (default ``channel``); ``name`` identifies
        the sender in :attr:`Received.source`."""
        p = BusPeer(self, channel, registry=registry, key=key, cipher=cipher,
                    name=name or f"{channel}#{next(self._ids)}", label=label or channel,
                    max_datagram=max_datagram, iv_source=iv_source)
        self._channels.setdefault(channel, []).append(p)
        return p

    def stream_server(self, address: str = "teamserver", *, registry: MessageRegistry,
                      key: str | bytes | None = None, cipher: int | str = LINK_CIPHER,
                      channel: str = "stream", drop_unauthenticated: bool = True,
                      iv_source: Callable[[int], bytes] = os.urandom) -> BusStreamServer:
        """Listen at ``address``; raises ValueError if a server is already there."""
        if address in self._servers:
            raise ValueError(f"a bus stream server already listens at {address!r}")
        srv = BusStreamServer(self, address, registry=registry, key=key, cipher=cipher,
                              channel=channel, drop_unauthenticated=drop_unauthenticated,
                              iv_source=iv_source)
        self._servers[address] = srv
        return srv

    def stream_client(self, address: str = "teamserver", *, registry: MessageRegistry,
                      key: str | bytes | None = None, cipher: int | str = LINK_CIPHER,
                      channel: str = "stream", name: str | None = None,
                      iv_source: Callable[[int], bytes] = os.urandom) -> BusStreamClient:
        """A client of the server at ``address`` (connects now, or on a later poll)."""
        return BusStreamClient(self, address, registry=registry, key=key, cipher=cipher,
                               channel=channel, name=name or f"client#{next(self._ids)}",
                               iv_source=iv_source)


class _BusEnd(CryptoSwitch):
    """Inbox, codec and events shared by every bus endpoint."""

    def __init__(self, bus: Bus, channel: str, registry: MessageRegistry, key, cipher,
                 max_frame: int, stats_name: str, iv_source, role: int | None = None):
        self.bus = bus
        self.channel = channel
        self.stats = S.DropStats(stats_name)
        self.secure = None
        if role is not None:                       # a stream end: secured when given a key
            key, self.secure = stream_crypto(key, cipher, role, self.stats)
            cipher = TEAM_CIPHER if key is None else cipher
        self.codec = FrameCodec(registry, key=key, cipher=cipher, max_frame=max_frame,
                                stats=self.stats, iv_source=iv_source)
        self._inbox: deque[tuple[bytes, Any]] = deque()
        self._events: deque[LinkEvent] = deque()
        self.closed = False

    def _poll(self) -> None:
        """Hook: make progress before receiving (stream clients connect here)."""

    def _event(self, kind: str, peer: Any) -> None:
        self._events.append(LinkEvent(kind, peer, self.channel, self.bus.now()))

    # -- secured streams ---------------------------------------------------------
    def _frame(self, conn, msg) -> tuple[bytes | None, bytes]:
        """``(frame to carry or None while the hello is awaited, what a tap sees)``."""
        if self.secure is None:
            frame = self.codec.encode(msg)
            return frame, frame
        message = self.codec.message_bytes(msg)
        return self.secure.seal(conn, message), self.codec.plain_frame(message)

    def _reply(self, conn, frame: bytes) -> None:
        """Carry ``frame`` to the peer of connection ``conn`` (secured streams)."""
        raise NotImplementedError

    def _open(self, frame: bytes, conn):
        if self.secure is None:
            return self.codec.try_decode(frame)
        message, replies, cause = self.secure.open(conn, frame)
        for reply in replies:
            self._reply(conn, reply)
        if message is None:
            return None, cause
        return self.codec.decode_message(message, 0x81)

    def _decode_inbox(self) -> list[tuple[Received | None, str | None, Any]]:
        out = []
        while self._inbox:
            frame, source = self._inbox.popleft()
            decoded, cause = self._open(frame, source)
            rec = None if decoded is None else Received.of(decoded, self.channel, source,
                                                           self.bus.now())
            out.append((rec, cause, source))
        return out

    def receive(self) -> list[Received]:
        self._poll()
        return [rec for rec, _c, _s in self._decode_inbox() if rec is not None]

    def events(self) -> list[LinkEvent]:
        self._poll()
        items = list(self._events)
        self._events.clear()
        return items

    def wait(self, timeout: float) -> bool:
        """Never blocks on the bus: True if frames or events are waiting."""
        self._poll()
        return bool(self._inbox or self._events)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()  # every subclass defines close()


class BusPeer(_BusEnd):
    """A broadcast endpoint on a bus channel (the UDP peer's twin)."""

    def __init__(self, bus: Bus, channel: str, *, registry, key, cipher, name: str, label: str,
                 max_datagram: int, iv_source):
        super().__init__(bus, label, registry, key, cipher, max_datagram,
                         f"{label} bus peer {name}", iv_source)
        self.bus_channel = channel
        self.name = name

    def send(self, msg) -> bool:
        """Encode ``msg`` and put it in every other endpoint's inbox on this channel."""
        if self.closed:
            return False
        frame = self.codec.encode(msg)
        self.bus._carry(self.bus_channel, self.name, frame)
        for p in self.bus._channels.get(self.bus_channel, ()):
            if p is not self:
                p._inbox.append((frame, self.name))
        return True

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            members = self.bus._channels.get(self.bus_channel, [])
            if self in members:
                members.remove(self)


class BusStreamServer(_BusEnd):
    """The TCP server's twin: clients get int ids; ``send(msg, to=None)``."""

    def __init__(self, bus: Bus, address: str, *, registry, key, cipher, channel: str,
                 drop_unauthenticated: bool, iv_source):
        super().__init__(bus, channel, registry, key, cipher, _STREAM_MAX_FRAME,
                         f"{channel} bus server {address}", iv_source, role=SERVER)
        self.address = address
        self.drop_unauthenticated = drop_unauthenticated
        self._clients: dict[int, BusStreamClient] = {}
        self._next_id = 1

    def _accept(self, client: BusStreamClient, hello: bytes | None = None) -> int:
        cid, self._next_id = self._next_id, self._next_id + 1
        self._clients[cid] = client
        self._event(CONNECTED, cid)
        if self.secure is not None:
            client._inbox.append((self.secure.connect(cid), self.address))
            if hello is not None:      # the client's hello, taken at once: no round trip on a bus
                self._open(hello, cid)
        return cid

    def _reply(self, conn, frame: bytes) -> None:
        client = self._clients.get(conn)
        if client is not None:
            client._inbox.append((frame, self.address))

    def clients(self) -> list[int]:
        return list(self._clients)

    def peer_address(self, client: int) -> str | None:
        c = self._clients.get(client)
        return c.name if c else None

    def send(self, msg, to: int | None = None) -> bool:
        targets = list(self._clients) if to is None else [to]
        sent = False
        for cid in targets:
            client = self._clients.get(cid)
            if client is None:
                continue
            frame, seen = self._frame(cid, msg)
            self.bus._carry(self.address, self.address, seen)
            if frame is not None:
                client._inbox.append((frame, self.address))
            sent = True
        return sent

    def disconnect(self, client: int) -> None:
        c = self._clients.pop(client, None)
        if c is not None:
            if self.secure is not None:
                self.secure.forget(client)
            self._event(DISCONNECTED, client)
            c._lost()

    def receive(self) -> list[Received]:
        out = []
        for rec, cause, cid in self._decode_inbox():
            if rec is not None:
                out.append(rec)
            elif cause in S.CRYPTO_CAUSES and self.drop_unauthenticated:
                self.disconnect(cid)
        return out

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            for cid in list(self._clients):
                self.disconnect(cid)
            if self.bus._servers.get(self.address) is self:
                del self.bus._servers[self.address]


class BusStreamClient(_BusEnd):
    """The TCP client's twin: connects to the bus server at ``address`` when it exists."""

    def __init__(self, bus: Bus, address: str, *, registry, key, cipher, channel: str,
                 name: str, iv_source):
        super().__init__(bus, channel, registry, key, cipher, _STREAM_MAX_FRAME,
                         f"{channel} bus client {name}", iv_source, role=CLIENT)
        self.address = address
        self.name = name
        self._server: BusStreamServer | None = None
        self._cid: int | None = None
        self.connections = 0
        self._poll()

    @property
    def connected(self) -> bool:
        return self._server is not None

    def _poll(self) -> None:
        if self._server is None and not self.closed:
            srv = self.bus._servers.get(self.address)
            if srv is not None and not srv.closed:
                hello = self.secure.connect(_SERVER) if self.secure is not None else None
                self._server, self._cid = srv, srv._accept(self, hello)
                self.connections += 1
                self._event(CONNECTED, self.address)
                if self.secure is not None and srv.secure is None:
                    srv._inbox.append((hello, self._cid))   # a server without a key drops it
                elif self.secure is not None:
                    # the server's hello is in the inbox already: take it now, so this
                    # client seals at once (a bus link costs no round trip, like before)
                    frame, _source = self._inbox.pop()
                    self.secure.open(_SERVER, frame)

    def _reply(self, conn, frame: bytes) -> None:
        if self._server is not None:
            self._server._inbox.append((frame, self._cid))

    def _open(self, frame: bytes, conn):
        return super()._open(frame, _SERVER)

    def _lost(self) -> None:
        if self._server is not None:
            self._server = self._cid = None
            if self.secure is not None:
                self.secure.forget(_SERVER)
            self._event(DISCONNECTED, self.address)

    def reconnect(self) -> None:
        """Drop the connection and connect again on the spot (like the TCP client)."""
        if self._server is not None:
            self._server.disconnect(self._cid)
            self._lost()
        self._poll()

    def send(self, msg) -> bool:
        if self.secure is None:
            self.codec.encode(msg)               # the caller's mistakes raise, connected or not
        self._poll()
        if self._server is None:
            return False
        frame, seen = self._frame(_SERVER, msg)
        self.bus._carry(self.address, self.name, seen)
        if frame is not None:
            self._server._inbox.append((frame, self._cid))
        return True

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            if self._server is not None:
                self._server.disconnect(self._cid)
