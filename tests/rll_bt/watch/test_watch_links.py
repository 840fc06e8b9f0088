"""What a process sends and receives, recorded: the team-server link over
real TCP with the team key (each end records the messages it sent and the
ones it received, decoded, never the wire bytes) and the refbox channels
(senders named by what the message tells)."""
from __future__ import annotations

import time

import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from games.replay import JsonDecoderFactory
from rll_bt import msgs
from rll_bt.agenttask import link as agent_link
from rll_bt.comm import Bus, MessageRegistry, StreamClient, StreamServer
from rll_bt.watch import LinkRecorder, wall_watch, watch_links
from rll_bt.watch.links import udp_sender

KEY = "link-key-42"
TM = msgs.message_set("team")
TEAM_REG = agent_link.registry()          # the robots' link: rll-bt's additions and AgentTask
LM = msgs.message_set("rcll2025")
RM = msgs.message_set("rcll2016")
REF_REG = MessageRegistry.from_message_set(RM)


def read(path):
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        meta = next(m.metadata for m in reader.iter_metadata() if m.name == "rll-bt")
        out = [(ch.topic, m.log_time, dec) for _s, ch, m, dec in reader.iter_decoded_messages(log_time_order=True)]
    return dict(meta), out


def pump(*transports, until, timeout=10.0):
    got = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for t in transports:
            t.wait(0.02)
            got += [(t, rx) for rx in t.receive()]
        if until(got):
            return got
    raise AssertionError(f"timed out; got {[rx.msg.DESCRIPTOR.name for _t, rx in got]}")


def test_each_end_of_the_secured_tcp_link_records_what_it_sent_and_received(tmp_path):
    ts_watch = wall_watch(record=tmp_path / "ts.mcap", live=None, name="ts", meta={"kind": "teamserver"})
    ag_watch = wall_watch(record=tmp_path / "agent.mcap", live=None, name="agent", meta={"kind": "agent"})
    server, _, _ = watch_links(ts_watch, "teamserver", link=StreamServer(0, host="127.0.0.1", registry=TEAM_REG,
                                                                          key=KEY))
    client, _, _ = watch_links(ag_watch, "robot2", link=StreamClient("127.0.0.1", server.port, registry=TEAM_REG,
                                                                    key=KEY))
    t_start = time.time()
    try:
        hello = TM.get("RobotHello")(robot_id=2, team_name="Testers", peer_name="R2")
        deadline = time.monotonic() + 10
        while not client.send(hello):         # until the connection (and its handshake) is up
            client.wait(0.05)
            server.receive()
            assert time.monotonic() < deadline
        got = pump(server, client, until=lambda g: any(rx.msg.DESCRIPTOR.name == "RobotHello" for _t, rx in g))
        cid = next(rx.source for t, rx in got if t is server)
        task = LM.get("AgentTask")(team_color=1, task_id=7, robot_id=2)
        task.retrieve.machine_id, task.retrieve.machine_point = "C-BS", "output"
        assert server.send(task, to=cid)
        pump(server, client, until=lambda g: any(rx.msg.DESCRIPTOR.name == "AgentTask" for _t, rx in g))
    finally:
        client.close()
        server.close()
        ts_watch.close()
        ag_watch.close()
    for path, sent, received in ((tmp_path / "agent.mcap", "/robot2/link/RobotHello", "/teamserver/link/AgentTask"),
                                 (tmp_path / "ts.mcap", "/teamserver/link/AgentTask", "/robot2/link/RobotHello")):
        meta, messages = read(path)
        topics = {t: d for t, _ns, d in messages}
        assert meta["clock"] == "wall" and {sent, received} <= set(topics), (path.name, sorted(topics))
        assert topics["/robot2/link/RobotHello"].peer_name == "R2"           # decoded, with its schema
        assert topics["/teamserver/link/AgentTask"].retrieve.machine_id == "C-BS"
        assert topics["/teamserver/link/AgentTask"].DESCRIPTOR.full_name == "llsf_msgs.AgentTask"
        # message times are Unix time: recordings of several processes of one machine line up
        assert all(abs(ns / 1e9 - t_start) < 60 for _t, ns, _d in messages)


def test_a_message_that_did_not_leave_is_not_recorded(tmp_path):
    watch = wall_watch(record=tmp_path / "a.mcap", live=None, name="agent")
    with StreamServer(0, host="127.0.0.1", registry=TEAM_REG, key=KEY) as probe:
        port = probe.port                      # a port nobody listens on any more
    link, _, _ = watch_links(watch, "robot1", link=StreamClient("127.0.0.1", port, registry=TEAM_REG, key=KEY))
    try:
        assert not link.send(TM.get("RobotHello")(robot_id=1, team_name="T", peer_name="R1"))
    finally:
        link.close()
        watch.close()
    assert watch.counts == {}


def test_refbox_channels_name_their_senders_by_the_message(tmp_path):
    from rll_bt.clock import SimClock
    clock = SimClock()
    bus = Bus(clock)
    refbox = bus.peer("public", registry=REF_REG, name="refbox")
    robot = bus.peer("cyan", registry=REF_REG, name="R3")
    watch = wall_watch(record=tmp_path / "ts.mcap", live=None, name="ts")
    rec = LinkRecorder(watch, "teamserver")
    public = rec.wrap(bus.peer("public", registry=REF_REG, name="teamserver"), "public")
    team = rec.wrap_team(lambda color: bus.peer(color, registry=REF_REG, name="teamserver"))("cyan")
    try:
        gs = RM.get("GameState")(state=2, phase=20)
        gs.game_time.sec, gs.game_time.nsec = 12, 0
        refbox.send(gs)
        beacon = RM.get("BeaconSignal")(number=3, team_name="Testers", peer_name="R3", seq=1)
        beacon.time.sec, beacon.time.nsec = 1, 0
        robot.send(beacon)
        report = RM.get("MachineReport")(team_color=1)
        assert team.send(report)
        assert [rx.msg.DESCRIPTOR.name for rx in public.receive()] == ["GameState"]
        assert [rx.msg.DESCRIPTOR.name for rx in team.receive()] == ["BeaconSignal"]
    finally:
        watch.close()
    assert set(watch.counts) == {"/refbox/public/GameState", "/robot3/cyan/BeaconSignal",
                                 "/teamserver/cyan/MachineReport"}
    assert udp_sender(RM.get("BeaconSignal")(number=2, team_name="x", peer_name="", seq=1)) == "robot2"


@pytest.mark.parametrize("name,topic", [("R12", "robot12"), ("Team Server", "team_server"), ("", "unknown")])
def test_sender_names(name, topic):
    from rll_bt.watch.links import sender_name
    assert sender_name(name) == topic
