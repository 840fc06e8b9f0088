"""SimTimeSync to a refbox's TCP stream: a framed TCP server of the comm
layer stands in for the refbox's port 4444 and decodes what arrives."""
from __future__ import annotations

import time

import pytest

from backends.sim.mps.timesync import TimeSync, split_time
from rll_bt import msgs
from rll_bt.comm import MessageRegistry, StreamServer


@pytest.fixture
def refbox_port():
    ms = msgs.message_set("rcll2025")
    server = StreamServer(0, host="127.0.0.1", registry=MessageRegistry.from_message_set(ms))
    yield server
    server.close()


def received(server, n, timeout=5.0):
    got = []
    deadline = time.monotonic() + timeout
    while len(got) < n and time.monotonic() < deadline:
        server.wait(0.05)
        got += [r.msg for r in server.receive()]
    return got


def test_split_time_keeps_nanoseconds_in_range():
    assert split_time(12.5) == (12, 500_000_000)
    assert split_time(0.9999999999) == (1, 0)
    assert split_time(3.0) == (3, 0)


def test_world_time_reaches_the_refbox_at_the_period_and_on_pause(refbox_port):
    sync = TimeSync("127.0.0.1", refbox_port.port, period=0.5, real_time_factor=2.0)
    try:
        assert sync.wait_connected(5)
        sent = [t for t in (0.0, 0.2, 0.5, 0.7, 1.0, 1.25) if sync.update(t)]
        assert sent == [0.0, 0.5, 1.0]
        assert sync.update(1.3, paused=True)                     # a pause goes out at once
        msgs_in = received(refbox_port, 4)
    finally:
        sync.close()
    assert [type(m).__name__ for m in msgs_in] == ["SimTimeSync"] * 4
    times = [m.sim_time.sec + m.sim_time.nsec * 1e-9 for m in msgs_in]
    assert times == pytest.approx([0.0, 0.5, 1.0, 1.3])
    assert [m.paused for m in msgs_in] == [False, False, False, True]
    assert {m.real_time_factor for m in msgs_in} == {2.0}


def test_a_stepping_world_is_followed(refbox_port):
    from backends.sim import World
    world = World("rcll2025", seed=0)
    sync = TimeSync("127.0.0.1", refbox_port.port, period=0.1)
    try:
        assert sync.wait_connected(5)
        for _ in range(50):
            world.step(0.02)
            sync.update(world.time)
        got = received(refbox_port, sync.sent)
        last = got[-1].sim_time.sec + got[-1].sim_time.nsec * 1e-9
    finally:
        sync.close()
        world.close()
    assert sync.sent == len(got) >= 9
    assert last == pytest.approx(world.time, abs=0.1)
    assert all(m.real_time_factor > 0 for m in got[1:])       # measured: world s per wall s
