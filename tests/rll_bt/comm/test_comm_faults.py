"""The fault layer: a lossy, slow, jittery, capped and cut radio link, seeded."""
from __future__ import annotations

import pytest

from rll_bt.clock import SimClock
from rll_bt.comm import CONNECTED, DISCONNECTED, Bus
from rll_bt.comm.faults import FaultyTransport, LinkFaults, parse_cut


def datagram(tm, faults, seed=1):
    clock = SimClock()
    bus = Bus(clock)
    far = bus.peer("public", registry=tm.registry(), name="far")
    robot = FaultyTransport(bus.peer("public", registry=tm.registry(), name="robot"), faults,
                            seed=seed, clock=clock)
    return clock, far, robot


def stream(tm, faults, seed=1):
    clock = SimClock()
    bus = Bus(clock)
    server = bus.stream_server("ts", registry=tm.registry())
    robot = FaultyTransport(bus.stream_client("ts", registry=tm.registry()), faults, seed=seed, clock=clock)
    robot.receive()
    assert [e.kind for e in robot.events()] == [CONNECTED]
    server.receive()
    server.events()
    return clock, server, robot


def run(clock, step, until, fn):
    while clock.now() < until:
        fn()
        clock.advance(step)


def test_datagram_loss_is_about_the_rate_and_both_ways(tm):
    clock, far, robot = datagram(tm, LinkFaults(loss=0.2))
    got_robot, got_far = [], []
    for i in range(2000):
        far.send(tm.Hello(name="gs", value=i))
        robot.send(tm.Other(x=i))
        got_robot += robot.receive()
        got_far += far.receive()
    assert 0.75 < len(got_robot) / 2000 < 0.85
    assert 0.75 < len(got_far) / 2000 < 0.85
    assert robot.counts["lost_in"] + len(got_robot) == 2000
    assert robot.counts["lost_out"] + len(got_far) == 2000


def test_delay_and_jitter_on_datagrams_reorder_them(tm):
    clock, far, robot = datagram(tm, LinkFaults(delay=2.0, jitter=0.2))
    sent = {}
    arrivals = []

    def tick():
        if clock.now() < 10.0:
            far.send(tm.Hello(name="x", value=len(sent)))
            sent[len(sent)] = clock.now()
        arrivals.extend((r.msg.value, r.time) for r in robot.receive())
    run(clock, 0.05, 20.0, tick)
    assert len(arrivals) == len(sent)
    delays = [t - sent[v] for v, t in arrivals]
    assert min(delays) > 1.4 and max(delays) < 2.7
    assert abs(sum(delays) / len(delays) - 2.0) < 0.05
    order = [v for v, _ in arrivals]
    assert order != sorted(order)                     # jitter lets frames overtake


def test_duplicates_and_reordering(tm):
    clock, far, robot = datagram(tm, LinkFaults(delay=0.5, duplicate=0.1, reorder=0.25))
    got = []
    for i in range(1000):
        far.send(tm.Hello(name="x", value=i))
        got += [r.msg.value for r in robot.receive()]
        clock.advance(0.01)
    clock.advance(1.0)
    got += [r.msg.value for r in robot.receive()]
    assert 1060 < len(got) < 1140 and len(set(got)) == 1000
    assert got != sorted(got)


def test_a_stream_loses_nothing_keeps_order_and_pays_for_losses_in_time(tm):
    clock, server, robot = stream(tm, LinkFaults(loss=0.2, delay=0.1))
    got, sent = [], {}

    def tick():
        if clock.now() < 5.0:
            sent[len(sent)] = clock.now()
            server.send(tm.Other(x=len(sent) - 1))
        got.extend((r.msg.x, r.time) for r in robot.receive())
    run(clock, 0.01, 30.0, tick)
    values = [v for v, _ in got]
    assert values == sorted(values) and len(values) == len(sent)
    assert robot.counts["retransmitted_in"] > 50
    late = [t - sent[v] for v, t in got]
    assert min(late) >= 0.1 - 1e-9 and max(late) > 0.3


def test_bandwidth_cap_queues_frames(tm):
    clock, far, robot = datagram(tm, LinkFaults(bandwidth=80_000))       # 10 kB/s
    blob = b"\0" * 956                               # about 1000 bytes a frame with the overhead
    for _ in range(20):
        far.send(tm.Hello(name="big", blob=blob))
    got = []
    run(clock, 0.1, 3.0, lambda: got.extend(r.time for r in robot.receive()))
    assert len(got) == 20
    assert 1.8 < got[-1] < 2.3                       # 20 kB at 10 kB/s


def test_a_cut_disconnects_a_stream_and_it_comes_back(tm):
    clock, server, robot = stream(tm, LinkFaults(cuts=((2.0, 5.0),)))
    log = []

    def tick():
        server.send(tm.Other(x=int(clock.now() * 10)))
        ok = robot.send(tm.Other(x=-1))
        log.append((clock.now(), robot.connected, ok, [r.msg.x for r in robot.receive()],
                    [e.kind for e in robot.events()], len(server.receive())))
    run(clock, 0.5, 8.0, tick)
    during = [e for e in log if 2.0 <= e[0] < 5.0]
    assert all(not connected and not ok and not got and not heard for _, connected, ok, got, _, heard in during)
    kinds = [k for e in log for k in e[4]]
    assert kinds == [DISCONNECTED, CONNECTED]
    after = [e for e in log if e[0] >= 5.0]
    assert all(e[1] and e[2] and e[3] and e[5] for e in after)


def test_a_stall_holds_a_stream_both_ways_and_loses_nothing(tm):
    """A stall (a chain of retransmissions): nothing arrives during it, what was due
    in it arrives at its end, in order; nothing is lost and the link stays up."""
    clock, server, robot = stream(tm, LinkFaults(delay=0.5, stalls=((2.0, 5.0),)))
    sent, to_robot, to_server = [], [], []

    def tick():
        sent.append(clock.now())
        server.send(tm.Other(x=len(sent) - 1))
        assert robot.send(tm.Other(x=len(sent) - 1))
        to_robot.extend((r.msg.x, clock.now()) for r in robot.receive())
        to_server.extend((r.msg.x, clock.now()) for r in server.receive())
        assert robot.connected and not robot.events()
    run(clock, 0.25, 8.0, tick)
    for got in (to_robot, to_server):
        assert [x for x, _ in got] == list(range(len(got))) and sent[len(got) - 1] >= 7.0 - 1e-9
        assert not [t for _x, t in got if 2.0 <= t < 5.0]                 # nothing during the stall
        assert [sent[x] for x, t in got if t == 5.0] == [1.5 + 0.25 * i for i in range(13)]   # sent 1.5-4.5


def test_a_cut_loses_datagrams_both_ways(tm):
    clock, far, robot = datagram(tm, LinkFaults(cuts=((1.0, 2.0),)))
    heard, sent = [], []

    def tick():
        sent.append(clock.now())
        far.send(tm.Hello(name="x", value=len(sent) - 1))
        robot.send(tm.Other(x=1))
        heard.extend(r.msg.value for r in robot.receive())
    run(clock, 0.1, 3.0, tick)
    cut = [i for i, t in enumerate(sent) if 1.0 <= t < 2.0]
    assert len(cut) >= 9 and heard == [i for i in range(len(sent)) if i not in cut]
    assert robot.counts["cut_out"] == len(cut) and robot.counts["cut_in"] == len(cut)


def test_the_same_seed_gives_the_same_faults(tm):
    def play(seed):
        clock, far, robot = datagram(tm, LinkFaults(loss=0.3, delay=0.3, jitter=0.2, duplicate=0.1), seed)
        got = []
        for i in range(300):
            far.send(tm.Hello(name="x", value=i))
            got += [(r.msg.value, r.time) for r in robot.receive()]
            clock.advance(0.02)
        return got
    assert play(7) == play(7)
    assert play(7) != play(8)


def test_perfect_faults_pass_everything_at_once(tm):
    clock, far, robot = datagram(tm, LinkFaults())
    far.send(tm.Hello(name="x"))
    assert [r.type_name for r in robot.receive()] == ["Hello"]


def test_settings_are_checked_and_cuts_parse():
    assert parse_cut("R2:300-330.5") == ("R2", 300.0, 330.5)
    for bad in ("R2:330-300", "R2:300", "300-330", "R2:a-b"):
        with pytest.raises(ValueError):
            parse_cut(bad)
    for kw in ({"loss": 1.0}, {"loss": -0.1}, {"delay": -1}, {"bandwidth": 0}, {"cuts": ((5.0, 4.0),)},
               {"stalls": ((5.0, 5.0),)}):
        with pytest.raises(ValueError):
            LinkFaults(**kw)


def test_a_games_net_faults_give_each_robot_its_link_faults_and_agent_options():
    from rll_bt.comm.faults import NetFaults
    net = NetFaults(loss=0.2, delay=2.0, jitter=0.2, cuts=(("R2", 30.0, 45.0), ("all", 100.0, 101.0)))
    r1, r2 = net.for_robot(1), net.for_robot(2, offset=10.0)
    assert (r1.loss, r1.delay, r1.jitter, r1.cuts) == (0.2, 2.0, 0.2, ((100.0, 101.0),))
    assert r2.cuts == ((40.0, 55.0), (110.0, 111.0))            # shifted onto the agent's clock
    assert NetFaults().for_robot(1) is None and NetFaults().perfect
    assert NetFaults(cuts=(("2", 1.0, 2.0),)).for_robot(1) is None  # only robot 2 is cut
    assert net.args(2) == ["--net-loss", "0.2", "--net-delay", "2.0", "--net-jitter", "0.2",
                           "--net-cut", "30-45", "--net-cut", "100-101"]
    with pytest.raises(ValueError, match="R<N>"):
        NetFaults(cuts=(("robot", 1.0, 2.0),))
    with pytest.raises(ValueError, match="loss"):
        NetFaults(loss=1.0)


def test_what_the_layer_holds_is_bounded(tm):
    clock, far, robot = datagram(tm, LinkFaults(delay=5.0))
    robot.max_held = 10
    for i in range(25):
        robot.send(tm.Other(x=i))
    assert len(robot._out) == 10 and robot.counts["overflow_out"] == 15
