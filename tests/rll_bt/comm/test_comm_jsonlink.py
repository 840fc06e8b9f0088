"""Framed JSON links (rll_bt.comm.jsonlink) on the shared socket code: calls and
replies, pushes kept in order, a slow reader never blocking the server, bad
frames, closed links and silence."""
from __future__ import annotations

import json
import socket
import struct
import threading
import time

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rll_bt.comm.jsonlink import MAX_MESSAGE, FramedClient, FramedServer, LinkClosed, frame, parse_address
from rll_bt.comm.sockets import LengthPrefixed


class Echo(FramedServer):
    """Replies {"id", "r": request}; "push" first pushes N frames, "silent" gets no reply."""

    def __init__(self):
        super().__init__()
        self.seen = []

    def answer(self, conn, body):
        req = json.loads(body)
        self.seen.append(req)
        if req.get("m") == "push":
            for i in range(req["n"]):
                self.push({"ev": i})
        if req.get("m") == "silent":
            return None
        return {"id": req["id"], "r": req}


class Served:
    """The server polled by a thread while the test calls."""

    def __init__(self, server):
        self.server = server
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stop.is_set():
            self.server.poll(0.005)

    def close(self):
        self.stop.set()
        self.thread.join(5)
        self.server.close()


@pytest.fixture
def served():
    s = Served(Echo())
    yield s
    s.close()


def test_calls_get_their_replies_and_pushes_keep_their_order(served):
    c = FramedClient("127.0.0.1", served.server.port, timeout=5.0)
    try:
        assert c.call({"m": "hello", "a": [1, 2.5, "x", None]})["r"]["a"] == [1, 2.5, "x", None]
        reply = c.call({"m": "push", "n": 50})         # pushes arrive before the reply
        assert reply["r"]["m"] == "push"
        assert [m["ev"] for m in c.pushed()] == list(range(50))
        assert c.pushed() == []
        assert [r["id"] for r in served.server.seen] == [1, 2]
    finally:
        c.close()


def test_a_big_value_crosses_whole(served):
    c = FramedClient("127.0.0.1", served.server.port)
    try:
        blob = "x" * (3 << 20)
        assert c.call({"m": "big", "blob": blob})["r"]["blob"] == blob
    finally:
        c.close()


def test_a_slow_reader_never_blocks_the_server():
    server = Echo()
    try:
        c = FramedClient("127.0.0.1", server.port)
        deadline = time.monotonic() + 5
        while not server.clients and time.monotonic() < deadline:
            server.poll(0.01)
        t0 = time.monotonic()
        for i in range(100000):                      # the client reads nothing meanwhile (~13 MB)
            server.push({"ev": i, "pad": "y" * 100})
        assert time.monotonic() - t0 < 10.0 and server.unsent > 0
        got = []
        deadline = time.monotonic() + 20
        while len(got) < 100000 and time.monotonic() < deadline:
            server.poll(0.005)
            got += [m["ev"] for m in c.pushed()]
        assert got == list(range(100000)) and server.unsent == 0
        c.close()
    finally:
        server.close()


def test_an_oversized_frame_drops_that_client_only(served):
    good = FramedClient("127.0.0.1", served.server.port)
    bad = socket.create_connection(("127.0.0.1", served.server.port))
    try:
        bad.sendall(struct.pack(">I", MAX_MESSAGE + 1) + b"{}")
        bad.settimeout(5)
        assert bad.recv(10) == b""                   # the server closed it
        assert good.call({"m": "still"})["r"]["m"] == "still"
    finally:
        bad.close()
        good.close()


def test_a_closed_server_is_a_clear_link_closed(served):
    c = FramedClient("127.0.0.1", served.server.port)
    assert c.call({"m": "x"})["id"] == 1
    served.close()
    with pytest.raises(LinkClosed, match="closed the link"):
        c.call({"m": "y"})
    assert c.closed
    with pytest.raises(LinkClosed):
        c.pushed()


def test_silence_is_a_timeout_not_a_hang(served):
    c = FramedClient("127.0.0.1", served.server.port, timeout=0.3)
    try:
        t0 = time.monotonic()
        with pytest.raises(TimeoutError):
            c.call({"m": "silent"})
        assert 0.25 < time.monotonic() - t0 < 3.0
    finally:
        c.close()


def test_nobody_listening_is_an_os_error():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    with pytest.raises(OSError):
        FramedClient("127.0.0.1", port, timeout=1.0)


def test_addresses():
    assert parse_address("10.0.0.2:4470") == ("10.0.0.2", 4470)
    assert parse_address(":4470") == ("127.0.0.1", 4470)
    for bad in ("host", "host:0", "host:70000", "host:x"):
        with pytest.raises(ValueError, match="HOST:PORT"):
            parse_address(bad)


@given(st.lists(st.binary(max_size=300), max_size=20), st.lists(st.integers(1, 64), min_size=1, max_size=10))
def test_length_prefixed_frames_survive_any_cutting(bodies, cuts):
    stream = b"".join(LengthPrefixed.frame(b) for b in bodies)
    cutter, out, i, k = LengthPrefixed(1000), [], 0, 0
    while i < len(stream):
        step = cuts[k % len(cuts)]
        out += cutter.feed(stream[i:i + step])
        i, k = i + step, k + 1
    assert out == bodies and cutter.broken is None


@given(st.binary(max_size=200))
def test_length_prefixed_garbage_never_raises(data):
    cutter = LengthPrefixed(64)
    frames = cutter.feed(data)
    assert all(len(f) <= 64 for f in frames)
    if cutter.broken:
        assert cutter.feed(b"more") == []


def test_frame_is_length_and_json():
    f = frame({"a": 1})
    assert f[:4] == struct.pack(">I", len(f) - 4) and json.loads(f[4:]) == {"a": 1}
