"""Wire bytes worked out by hand from the fact sheet's field numbers and wire types.

A wrong field number, label or type in a .proto changes these bytes.
"""
from __future__ import annotations

import struct

import pytest
from google.protobuf.message import EncodeError

from rll_bt import msgs


# -- a tiny protobuf encoder, from the wire-format rules -------------------
def varint(n: int) -> bytes:
    n &= (1 << 64) - 1                      # negative int64 -> ten bytes
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def key(field: int, wire_type: int) -> bytes:
    return varint(field << 3 | wire_type)


def vi(field: int, n: int) -> bytes:            # wire type 0
    return key(field, 0) + varint(n)


def ld(field: int, payload: bytes | str) -> bytes:   # wire type 2
    if isinstance(payload, str):
        payload = payload.encode()
    return key(field, 2) + varint(len(payload)) + payload


def f32(field: int, x: float) -> bytes:          # wire type 5
    return key(field, 5) + struct.pack("<f", x)


R16 = msgs.message_set("rcll2016")
R25 = msgs.message_set("rcll2025")
TEAM = msgs.message_set("team")


def test_gamestate_bytes_written_out_by_hand():
    gs = R16.GameState(state=R16.GameState.RUNNING, phase=R16.GameState.PRODUCTION,
                       points_cyan=12, team_cyan="Carologistics")
    gs.game_time.sec = 5
    gs.game_time.nsec = 0
    expected = bytes.fromhex(
        "0a04" "0805" "1000"      # 1: game_time {1: sec=5, 2: nsec=0}
        "1802"                    # 3: state RUNNING(2)
        "201e"                    # 4: phase PRODUCTION(30)
        "280c"                    # 5: points_cyan 12
        "320d") + b"Carologistics"  # 6: team_cyan, 13 bytes
    assert gs.SerializeToString() == expected
    assert R25.GameState.FromString(expected).phase == R25.GameState.PRODUCTION


def test_gamestate_2025_field_layout():
    gs = R25.GameState(state=R25.GameState.PAUSED, phase=R25.GameState.SETUP,
                       points_magenta=3, team_magenta="GRIPS",
                       field_height=8, field_width=7, field_mirrored=True)
    gs.game_time.sec = 1
    gs.game_time.nsec = 2
    expected = (ld(1, vi(1, 1) + vi(2, 2)) + vi(3, 3) + vi(4, 10) + vi(8, 3) + ld(9, "GRIPS")
                + vi(10, 8) + vi(11, 7) + vi(12, 1))
    assert gs.SerializeToString() == expected


def test_beacon_signal_bytes():
    b = R16.BeaconSignal(seq=7, number=2, team_name="GRIPS", peer_name="R2",
                         team_color=R16.enum("Team").Value("MAGENTA"))
    b.time.sec = 1_700_000_000
    b.time.nsec = 500
    b.pose.timestamp.sec = 1
    b.pose.timestamp.nsec = 2
    b.pose.x, b.pose.y, b.pose.ori = 1.5, -2.0, 0.25
    pose = ld(1, vi(1, 1) + vi(2, 2)) + f32(2, 1.5) + f32(3, -2.0) + f32(4, 0.25)
    expected = (ld(1, vi(1, 1_700_000_000) + vi(2, 500)) + vi(2, 7) + ld(4, "GRIPS")
                + ld(5, "R2") + vi(6, 1) + ld(7, pose) + vi(8, 2))
    assert b.SerializeToString() == expected
    # the same bytes are a valid 2025 beacon (fields 9/10 only added)
    assert R25.BeaconSignal.FromString(expected).team_name == "GRIPS"


def test_beacon_2025_carries_agent_task_and_finished_tasks():
    b = R25.BeaconSignal(seq=1, number=3, team_name="T", peer_name="P")
    b.time.sec, b.time.nsec = 0, 0
    b.task.team_color = 0
    b.task.task_id = 9
    b.task.robot_id = 3
    b.task.move.waypoint = "C_Z33"
    b.finished_tasks.add(TaskId=8, successful=True)
    task = vi(1, 0) + vi(2, 9) + vi(3, 3) + ld(4, ld(1, "C_Z33"))
    expected = (ld(1, vi(1, 0) + vi(2, 0)) + vi(2, 1) + ld(4, "T") + ld(5, "P") + vi(8, 3)
                + ld(9, task) + ld(10, vi(1, 8) + vi(2, 1)))
    assert b.SerializeToString() == expected


def test_prepare_machine_ds_2016_gate_vs_2025_order_id():
    p16 = R16.PrepareMachine(team_color=0, machine="C-DS")
    p16.instruction_ds.gate = 2
    bytes16 = bytes.fromhex("0800" "1204") + b"C-DS" + bytes.fromhex("2a02" "0802")
    assert p16.SerializeToString() == bytes16

    p25 = R25.PrepareMachine(team_color=0, machine="C-DS", sent_at=1_700_000_000)
    p25.instruction_ds.order_id = 5
    bytes25 = vi(1, 0) + ld(2, "C-DS") + ld(5, vi(2, 5)) + vi(15, 1_700_000_000)
    assert p25.SerializeToString() == bytes25
    assert bytes25[-6] == 0x78          # field 15, varint

    # A 2016 DS instruction lacks the 2025 order_id: not initialised, not re-sendable.
    old = R25.PrepareMachine.FromString(bytes16)
    assert not old.IsInitialized()
    assert "instruction_ds.order_id" in old.FindInitializationErrors()
    with pytest.raises(EncodeError):
        old.SerializeToString()


def test_prepare_machine_other_instructions():
    p = R16.PrepareMachine(team_color=1, machine="M-BS")
    p.instruction_bs.side = R16.enum("MachineSide").Value("OUTPUT")
    p.instruction_bs.color = R16.enum("BaseColor").Value("BASE_SILVER")
    assert p.SerializeToString() == vi(1, 1) + ld(2, "M-BS") + ld(4, vi(1, 2) + vi(2, 3))

    p = R25.PrepareMachine(team_color=0, machine="C-SS")
    p.instruction_ss.operation = R25.enum("SSOp").Value("RETRIEVE")
    p.instruction_ss.shelf, p.instruction_ss.slot = 4, 6
    p.instruction_ss.wp_description = "x"
    assert p.SerializeToString() == (vi(1, 0) + ld(2, "C-SS")
                                     + ld(8, vi(1, 2) + vi(2, 4) + vi(3, 6) + ld(10, "x")))


def test_order_2025_competitive_and_unconfirmed():
    o = R25.Order(id=11, complexity=0, base_color=4, cap_color=2, quantity_requested=1,
                  quantity_delivered_cyan=0, quantity_delivered_magenta=1,
                  delivery_period_begin=1020, delivery_period_end=1200, delivery_gate=3,
                  competitive=True)
    o.ring_colors.append(2)
    d = o.unconfirmed_deliveries.add(id=4, team=1)
    d.delivery_time.sec, d.delivery_time.nsec = 60, 0
    expected = (vi(1, 11) + vi(2, 0) + vi(3, 4) + vi(4, 2) + vi(5, 2) + vi(6, 1) + vi(7, 0)
                + vi(8, 1) + vi(9, 1020) + vi(10, 1200) + vi(11, 3)
                + ld(12, vi(1, 4) + vi(2, 1) + ld(3, vi(1, 60) + vi(2, 0))) + vi(13, 1))
    assert o.SerializeToString() == expected


def test_machine_report_2016_vs_2025():
    r = R16.MachineReport(team_color=0)
    r.machines.add(name="C-CS1", type="abcdefgh", zone=R16.enum("Zone").Value("Z7"))
    assert r.SerializeToString() == ld(1, ld(1, "C-CS1") + ld(2, "abcdefgh") + vi(3, 7)) + vi(2, 0)

    r = R25.MachineReport(team_color=1)
    r.machines.add(name="M-RS2", zone=R25.enum("Zone").Value("M_Z45"), rotation=135)
    assert r.SerializeToString() == ld(1, ld(1, "M-RS2") + vi(3, 1045) + vi(4, 135)) + vi(2, 1)


def test_machine_info_2025_tags_and_rotation():
    m = R25.Machine(name="C-BS", input_tag=122, output_tag=121, rotation=270,
                    zone=R25.enum("Zone").Value("C_Z11"))
    assert m.SerializeToString() == (ld(1, "C-BS") + vi(5, 122) + vi(6, 121) + vi(11, 11)
                                     + vi(12, 270))


def test_agent_task_bytes():
    t = R25.AgentTask(team_color=0, task_id=1, robot_id=2, order_id=4)
    t.deliver.machine_id, t.deliver.machine_point = "C-DS", "input"
    assert t.SerializeToString() == (vi(1, 0) + vi(2, 1) + vi(3, 2) + ld(6, ld(1, "C-DS") + ld(2, "input"))
                                     + vi(10, 4))
