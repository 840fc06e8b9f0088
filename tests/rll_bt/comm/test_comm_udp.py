"""UDP peers on loopback with split ports, self-drop, size limit and team-channel crypto."""
from __future__ import annotations

import socket
import threading
import time

import pytest

from rll_bt.comm import FrameTooLarge, UdpPeer
from rll_bt.comm import stats as S
from tests.support.comm import free_udp_ports

KEY = "randomkey"


def collect(peer, n, timeout=3.0):
    out, deadline = [], time.monotonic() + timeout
    while len(out) < n and time.monotonic() < deadline:
        peer.wait(0.05)
        out += peer.receive()
    return out


def settle(peer, seconds=0.2):
    """Everything that arrives within ``seconds`` (for asserting that nothing does)."""
    return collect(peer, 10**9, timeout=seconds)


@pytest.fixture
def pair(tm):
    """Two plain peers with split ports: a sends to b's receive port and vice versa."""
    pa, pb = free_udp_ports(2)
    a = UdpPeer("127.0.0.1", send_port=pb, recv_port=pa, registry=tm.registry(), channel="public")
    b = UdpPeer("127.0.0.1", send_port=pa, recv_port=pb, registry=tm.registry(), channel="public")
    yield a, b
    a.close()
    b.close()


def test_split_ports_both_directions(pair, tm):
    a, b = pair
    assert a.send(tm.Hello(name="from-a", value=1))
    assert b.send(tm.Other(x=2))
    got_b, got_a = collect(b, 1), collect(a, 1)
    assert [r.msg.name for r in got_b] == ["from-a"]
    assert got_b[0].channel == "public" and got_b[0].source == ("127.0.0.1", a.recv_port)
    assert got_b[0].type_name == "Hello" and got_b[0].cipher == 0
    assert [r.msg.x for r in got_a] == [2]


def test_many_datagrams_arrive_in_order(pair, tm):
    a, b = pair
    for i in range(50):
        a.send(tm.Hello(name="n", value=i))
    got = collect(b, 50)
    assert [r.msg.value for r in got] == list(range(50))


def test_own_datagrams_dropped_but_same_host_other_port_received(tm):
    (p, q) = free_udp_ports(2)
    me = UdpPeer("127.0.0.1", p, registry=tm.registry())          # single port p
    other = UdpPeer("127.0.0.1", send_port=p, recv_port=q, registry=tm.registry())
    try:
        me.send(tm.Hello(name="echo"))      # goes to 127.0.0.1:p, i.e. back to me
        other.send(tm.Hello(name="other"))  # from 127.0.0.1:q
        got = collect(me, 1) + settle(me)
        assert [r.msg.name for r in got] == ["other"]
        assert me.stats.own == 1 and me.stats.total == 0
        assert me.is_own(("127.0.0.1", p)) and not me.is_own(("127.0.0.1", q))
    finally:
        me.close()
        other.close()


def test_oversize_send_is_a_clear_error_and_oversize_datagram_dropped(pair, tm):
    a, b = pair
    with pytest.raises(FrameTooLarge, match="1024-byte limit"):
        a.send(tm.Hello(name="big", blob=b"x" * 2000))
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    raw.sendto(b"\x02\x00\x00\x00" + (1092).to_bytes(4, "big") + bytes(1092), ("127.0.0.1", b.recv_port))
    raw.sendto(b"junk", ("127.0.0.1", b.recv_port))
    raw.close()
    assert settle(b, 0.3) == []
    assert b.stats.as_dict() == {S.OVERSIZE: 1, S.TOO_SHORT: 1}


def test_team_channel_encryption(tm):
    pa, pb, pc = free_udp_ports(3)
    a = UdpPeer("127.0.0.1", pb, pa, registry=tm.registry(), channel="team", key=KEY)
    b = UdpPeer("127.0.0.1", pa, pb, registry=tm.registry(), channel="team", key=KEY)
    plain = UdpPeer("127.0.0.1", pb, pc, registry=tm.registry(), channel="team")
    wrong = UdpPeer("127.0.0.1", pb, 0, registry=tm.registry(), channel="team", key="nope")
    try:
        plain.send(tm.Hello(name="plain"))
        wrong.send(tm.Hello(name="wrong"))
        a.send(tm.Hello(name="secret"))
        got = collect(b, 1) + settle(b)
        assert [r.msg.name for r in got] == ["secret"] and got[0].cipher == 2
        assert b.stats.count(S.PLAIN_ON_ENCRYPTED) == 1 and b.stats.total == 2
        # and the reverse: a plain peer drops the team's encrypted frames
        b.send_port = pc
        b.send(tm.Hello(name="to-plain"))
        assert settle(plain, 0.3) == []
        assert plain.stats.as_dict() == {S.ENCRYPTED_ON_PLAIN: 1}
        # switching crypto on later (what a robot does once GameState names its team)
        plain.set_crypto(KEY)
        b.send(tm.Hello(name="now-readable"))
        assert [r.msg.name for r in collect(plain, 1)] == ["now-readable"]
    finally:
        for p in (a, b, plain, wrong):
            p.close()


def test_threaded_callback_mode(pair, tm):
    a, b = pair
    got, done = [], threading.Event()

    def on_msg(rec):
        got.append(rec.msg.value)
        if len(got) == 3:
            done.set()

    b.start(on_msg)
    for i in range(3):
        a.send(tm.Hello(name="t", value=i))
    assert done.wait(3.0)
    b.stop()
    assert got == [0, 1, 2] and b.receive() == []


def test_bind_conflict_raises_oserror_and_send_failure_returns_false(tm):
    blocker = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    blocker.bind(("0.0.0.0", 0))  # no SO_REUSEADDR: a second bind must fail
    port = blocker.getsockname()[1]
    try:
        with pytest.raises(OSError):
            UdpPeer("127.0.0.1", port, registry=tm.registry())
    finally:
        blocker.close()
    p = UdpPeer("127.0.0.1", 9, 0, registry=tm.registry())
    p.send_port = 0  # the OS refuses port 0 (EINVAL): send reports it instead of raising
    try:
        assert p.send(tm.Hello(name="x")) is False
    finally:
        p.close()
