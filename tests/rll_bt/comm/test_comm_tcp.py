"""Framed TCP client/server: exchange, per-client send, reconnect, encrypted link."""
from __future__ import annotations

import socket
import struct
import time

import pytest

from rll_bt.clock import SimClock
from rll_bt.comm import CONNECTED, DISCONNECTED, FrameCodec, StreamClient, StreamServer
from rll_bt.comm import stats as S
from rll_bt.comm.framing import StreamReassembler
from rll_bt.comm.secure import CLIENT, LINK_CIPHER, SEALED, SecureSession

KEY = "teamkey"


def until(cond, *transports, timeout=3.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return True
        for t in transports:
            t.wait(0.01)
    return cond()


class Inbox:
    """Polls transports and keeps what arrived, per transport."""

    def __init__(self, *transports):
        self.ts = transports
        self.got = {id(t): [] for t in transports}
        self.ev = {id(t): [] for t in transports}

    def pump(self):
        for t in self.ts:
            self.got[id(t)] += t.receive()
            self.ev[id(t)] += t.events()

    def wait_for(self, cond, timeout=3.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.pump()
            if cond():
                return True
            for t in self.ts:
                t.wait(0.005)
        return cond()

    def msgs(self, t):
        return self.got[id(t)]

    def events(self, t):
        return [(e.kind, e.peer) for e in self.ev[id(t)]]


@pytest.fixture
def server(tm):
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1")
    yield srv
    srv.close()


def test_exchange_and_per_client_send(server, tm):
    c1 = StreamClient("127.0.0.1", server.port, registry=tm.registry())
    c2 = StreamClient("127.0.0.1", server.port, registry=tm.registry())
    box = Inbox(server, c1, c2)
    try:
        assert box.wait_for(lambda: len(server.clients()) == 2 and c1.connected and c2.connected)
        assert box.events(c1) == [(CONNECTED, ("127.0.0.1", server.port))]
        assert c1.send(tm.TeamCmd(robot=1, text="hello")) and c2.send(tm.TeamCmd(robot=2))
        assert box.wait_for(lambda: len(box.msgs(server)) == 2)
        by_robot = {r.msg.robot: r.source for r in box.msgs(server)}
        assert set(by_robot) == {1, 2} and set(by_robot.values()) == set(server.clients())
        # reply to robot 1 only, then to everyone
        assert server.send(tm.Other(x=1), to=by_robot[1])
        assert server.send(tm.Other(x=99))
        assert box.wait_for(lambda: len(box.msgs(c1)) == 2 and len(box.msgs(c2)) == 1)
        assert [r.msg.x for r in box.msgs(c1)] == [1, 99]
        assert [r.msg.x for r in box.msgs(c2)] == [99]
        assert server.send(tm.Other(x=5), to=12345) is False
        assert server.peer_address(by_robot[2])[0] == "127.0.0.1"
        # a client leaving is an event on the server
        c2.close()
        assert box.wait_for(lambda: (DISCONNECTED, by_robot[2]) in box.events(server))
        assert server.clients() == [by_robot[1]]
    finally:
        c1.close()
        c2.close()


def test_large_and_many_frames_over_stream(server, tm):
    c = StreamClient("127.0.0.1", server.port, registry=tm.registry())
    box = Inbox(server, c)
    try:
        assert c.wait_connected(3.0)
        big = b"y" * 200_000  # no 1024-byte limit on streams
        for i in range(20):
            assert c.send(tm.Hello(name="big", value=i, blob=big))
        assert box.wait_for(lambda: len(box.msgs(server)) == 20, timeout=5.0)
        assert [r.msg.value for r in box.msgs(server)] == list(range(20))
        assert all(r.msg.blob == big for r in box.msgs(server))
    finally:
        c.close()


def test_client_reconnects_with_backoff_after_server_restart(tm):
    clock = SimClock()
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1")
    port = srv.port
    c = StreamClient("127.0.0.1", port, registry=tm.registry(), clock=clock,
                     backoff_initial=1.0, backoff_max=4.0)
    box = Inbox(c)
    try:
        assert until(lambda: c.receive() == [] and c.connected, c, srv)
        srv.close()
        assert box.wait_for(lambda: (DISCONNECTED, ("127.0.0.1", port)) in box.events(c))
        assert not c.connected and c.send(tm.Hello(name="lost")) is False
        # no server: failed attempts back off on the client's clock (1 s, then 2 s)
        clock.advance(1.0)
        c.receive()
        assert until(lambda: c.receive() == [] and (c.retry_at or 0) > clock.now(), c)
        assert c.retry_at - clock.now() == pytest.approx(2.0)
        srv = StreamServer(port, registry=tm.registry(), host="127.0.0.1")
        c.receive()
        assert not c.connected  # still backing off: the clock has not moved
        clock.advance(2.0)
        box2 = Inbox(srv, c)
        assert box2.wait_for(lambda: c.connected and len(srv.clients()) == 1)
        assert c.connections == 2
        assert c.send(tm.Hello(name="back"))
        assert box2.wait_for(lambda: [r.msg.name for r in box2.msgs(srv)] == ["back"])
    finally:
        c.close()
        srv.close()


@pytest.mark.parametrize("cipher,wire,failure", [(LINK_CIPHER, SEALED, S.AUTH_FAILURE),
                                                  ("aes-128-cbc", 2, S.DECRYPT_FAILURE)])
def test_encrypted_link_wrong_key_client_can_neither_read_nor_task(tm, cipher, wire, failure):
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1", key=KEY, cipher=cipher)
    good = StreamClient("127.0.0.1", srv.port, registry=tm.registry(), key=KEY, cipher=cipher)
    bad = StreamClient("127.0.0.1", srv.port, registry=tm.registry(), key="guess", cipher=cipher,
                       backoff_initial=10.0)
    box = Inbox(srv, good, bad)
    try:
        assert box.wait_for(lambda: len(srv.clients()) == 2 and good.connected and bad.connected)
        srv.send(tm.TeamCmd(robot=7, text="task"))
        assert box.wait_for(lambda: len(box.msgs(good)) == 1)
        assert box.msgs(good)[0].msg.text == "task" and box.msgs(good)[0].cipher == wire
        assert box.wait_for(lambda: bad.stats.count(failure) == 1)
        assert box.msgs(bad) == []
        # the wrong-key client's frames are dropped and it is disconnected
        bad.send(tm.TeamCmd(robot=66, text="fake result"))
        good.send(tm.TeamCmd(robot=7, text="real result"))
        assert box.wait_for(lambda: len(srv.clients()) == 1 and len(box.msgs(srv)) == 1)
        assert [r.msg.text for r in box.msgs(srv)] == ["real result"]
        assert srv.stats.count(failure) == 1
        assert box.wait_for(lambda: not bad.connected)
    finally:
        for t in (good, bad, srv):
            t.close()


def _raw_secured_client(port, key):
    """A hand-driven client of the secured link on a raw socket: (socket, session)."""
    raw = socket.create_connection(("127.0.0.1", port), timeout=3.0)
    session = SecureSession(key, CLIENT)
    raw.sendall(session.hello())
    reader = StreamReassembler()
    while not session.ready:
        for frame in reader.feed(raw.recv(4096)):
            session.open(frame)
    return raw, session


def test_replayed_and_altered_frames_are_dropped_and_counted(tm):
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1", key=KEY)
    srv.start()                                   # it reads in its own thread: the handshake needs it
    box = Inbox(srv)
    raw, session = _raw_secured_client(srv.port, KEY)
    try:
        codec = srv.codec
        first = session.seal(codec.message_bytes(tm.TeamCmd(robot=7, text="done 1")))
        raw.sendall(first + first)                                  # the same frame again: a replay
        assert box.wait_for(lambda: srv.stats.count(S.REPLAY) == 1)
        second = bytearray(session.seal(codec.message_bytes(tm.TeamCmd(robot=7, text="done 2"))))
        second[-3] ^= 0x20                                          # altered on the way
        raw.sendall(bytes(second))
        assert box.wait_for(lambda: srv.stats.count(S.AUTH_FAILURE) == 1)
        assert [r.msg.text for r in box.msgs(srv)] == ["done 1"]
        assert box.wait_for(lambda: srv.clients() == [])            # altered: disconnected
    finally:
        raw.close()
        srv.close()


def test_a_team_server_without_the_key_cannot_task_a_robot(tm):
    fake = StreamServer(0, registry=tm.registry(), host="127.0.0.1", key="not the team key")
    robot = StreamClient("127.0.0.1", fake.port, registry=tm.registry(), key=KEY)
    box = Inbox(fake, robot)
    try:
        assert box.wait_for(lambda: robot.connected and fake.clients())
        fake.send(tm.TeamCmd(robot=1, text="drive off the field"))
        assert box.wait_for(lambda: robot.stats.count(S.AUTH_FAILURE) == 1)
        assert box.msgs(robot) == []
    finally:
        robot.close()
        fake.close()


def test_plain_client_on_encrypted_server_is_dropped(tm):
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1", key=KEY)
    plain = StreamClient("127.0.0.1", srv.port, registry=tm.registry(), backoff_initial=10.0)
    box = Inbox(srv, plain)
    try:
        assert plain.wait_connected(3.0) and box.wait_for(lambda: len(srv.clients()) == 1)
        plain.send(tm.TeamCmd(robot=1))
        assert box.wait_for(lambda: srv.clients() == [])
        assert box.msgs(srv) == [] and srv.stats.as_dict() == {S.PLAIN_ON_ENCRYPTED: 1}
    finally:
        plain.close()
        srv.close()


def test_garbage_stream_is_counted_and_the_peer_disconnected(server, tm):
    raw = socket.create_connection(("127.0.0.1", server.port))
    box = Inbox(server)
    try:
        assert box.wait_for(lambda: len(server.clients()) == 1)
        good = FrameCodec(tm.registry()).encode(tm.Hello(name="ok"))
        raw.sendall(good + b"\x07\xd0\x00\x01" + struct.pack(">I", 3) + b"abc")  # a v1 header
        assert box.wait_for(lambda: server.clients() == [])
        assert [r.msg.name for r in box.msgs(server)] == ["ok"]
        assert server.stats.as_dict() == {S.BAD_VERSION: 1}
    finally:
        raw.close()


def test_threaded_server(server, tm):
    got = []
    server.start(got.append)
    c = StreamClient("127.0.0.1", server.port, registry=tm.registry())
    try:
        assert c.wait_connected(3.0)
        c.send(tm.Hello(name="threaded"))
        assert until(lambda: len(got) == 1, c)
        assert got[0].msg.name == "threaded"
    finally:
        server.stop()
        c.close()


def test_client_reconnect_drops_a_silent_link_and_connects_again(tm):
    clock = SimClock()
    srv = StreamServer(0, registry=tm.registry(), host="127.0.0.1")
    c = StreamClient("127.0.0.1", srv.port, registry=tm.registry(), clock=clock, backoff_initial=5.0)
    try:
        box = Inbox(srv, c)
        assert box.wait_for(lambda: c.connected and len(srv.clients()) == 1)
        first = srv.clients()[0]
        c.reconnect()                       # no backoff wait, though the clock stands still
        assert box.wait_for(lambda: c.connections == 2 and c.connected
                            and srv.clients() and srv.clients()[0] != first)
        assert c.send(tm.Hello(name="again"))
        assert box.wait_for(lambda: [r.msg.name for r in box.msgs(srv)] == ["again"])
    finally:
        c.close()
        srv.close()
