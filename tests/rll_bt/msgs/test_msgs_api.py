"""The public API of rll_bt.msgs and living with both refbox sets in one process."""
from __future__ import annotations

import pytest
from google.protobuf.message import DecodeError, EncodeError

from rll_bt import msgs


def test_profiles_and_sets():
    assert msgs.PROFILES == ("rcll2016", "rcll2025")
    assert msgs.SETS == ("rcll2016", "rcll2025", "team")


def test_unknown_set_is_a_value_error_listing_the_known_ones():
    with pytest.raises(ValueError) as exc:
        msgs.message_set("rcll2019")
    for name in msgs.SETS:
        assert name in str(exc.value)


def test_message_sets_are_cached():
    assert msgs.message_set("rcll2016") is msgs.message_set("rcll2016")


def test_lookup():
    ms = msgs.message_set("rcll2016")
    assert ms.name == "rcll2016"
    assert ms.GameState is ms.get("GameState") is ms.get("llsf_msgs.GameState")
    assert ms.all_classes["Time"] is ms.Time
    assert "Time" not in ms.classes and "GameState" in ms.classes
    assert "GameState" in ms
    with pytest.raises(KeyError, match="rcll2016 has no message 'Nope'"):
        ms.get("Nope")
    with pytest.raises(AttributeError):
        _ = ms.Nope
    # top-level enums are reachable as attributes and through enum()
    assert ms.Team is ms.enum("Team")
    assert ms.enum("Team").Name(1) == "MAGENTA"
    assert ms.enum("GameState.Phase").Value("SETUP") == 10
    with pytest.raises(KeyError, match="no enum"):
        ms.enum("Colour")


def test_comp_type_and_decode():
    ms = msgs.message_set("rcll2025")
    assert ms.comp_type(ms.AgentTask) == (8000, 502)
    assert ms.comp_type(ms.Time()) is None
    assert ms.by_comp_type[(2000, 20)] is ms.GameState
    gs = ms.GameState(state=2, phase=30)
    gs.game_time.sec, gs.game_time.nsec = 3, 4
    assert ms.decode(2000, 20, gs.SerializeToString()) == gs
    with pytest.raises(KeyError, match="COMP_ID 2000 MSG_TYPE 9999"):
        ms.decode(2000, 9999, b"")
    with pytest.raises(DecodeError):
        ms.decode(2000, 20, b"\x0a\x05\x08")          # truncated length-delimited field


def test_both_refbox_sets_in_one_process():
    a, b = msgs.message_set("rcll2016"), msgs.message_set("rcll2025")
    assert a.GameState is not b.GameState
    assert a.GameState.DESCRIPTOR.full_name == b.GameState.DESCRIPTOR.full_name == \
        "llsf_msgs.GameState"
    assert a.pool is not b.pool
    # each class sees its own set's fields
    assert "field_mirrored" not in a.GameState.DESCRIPTOR.fields_by_name
    assert "field_mirrored" in b.GameState.DESCRIPTOR.fields_by_name
    assert a.enum("Zone").Value("Z24") == 24
    assert b.enum("Zone").Value("M_Z78") == 1078
    assert "Z1" not in b.enum("Zone").keys()
    # messages of one set are not accepted where the other set's type is expected
    m = b.Machine(name="C-CS1")
    with pytest.raises(TypeError):
        a.MachineInfo().machines.append(m)


def test_2016_order_info_without_competitive():
    a, b = msgs.message_set("rcll2016"), msgs.message_set("rcll2025")
    info = a.OrderInfo()
    info.orders.add(id=1, complexity=0, base_color=1, cap_color=2, quantity_requested=1,
                    quantity_delivered_cyan=0, quantity_delivered_magenta=0,
                    delivery_period_begin=0, delivery_period_end=900, delivery_gate=2)
    data = info.SerializeToString()

    old = a.OrderInfo.FromString(data)
    assert old.IsInitialized() and old == info

    new = b.OrderInfo.FromString(data)
    assert not new.IsInitialized()
    assert new.FindInitializationErrors() == ["orders[0].competitive"]
    with pytest.raises(EncodeError):
        new.SerializeToString()


def test_to_dict_from_dict():
    ms = msgs.message_set("rcll2016")
    m = ms.Machine(name="C-RS1", type="RS", zone=ms.enum("Zone").Value("Z5"),
                   exploration_type_state=ms.enum("ExplorationState").Value("CORRECT_REPORT"))
    m.ring_colors.extend([1, 3])
    d = msgs.to_dict(m)
    assert d == {"name": "C-RS1", "type": "RS", "zone": "Z5", "ring_colors": ["RING_BLUE",
                 "RING_ORANGE"], "exploration_type_state": "CORRECT_REPORT"}
    assert msgs.from_dict(ms, "Machine", d) == m
    assert msgs.from_dict("rcll2016", ms.Machine, d) == m


@pytest.mark.parametrize("data,match", [
    ({"nosuch": 1}, "rcll2016.GameState"),
    ({"state": "SLEEPING"}, "rcll2016.GameState"),
    ({"points_cyan": "many"}, "rcll2016.GameState"),
    ({"points_cyan": -1}, "rcll2016.GameState"),
    ({"game_time": 5}, "rcll2016.GameState"),
    ([1, 2], "expected a JSON object"),
])
def test_from_dict_rejects_bad_input_with_value_error(data, match):
    with pytest.raises(ValueError, match=match):
        msgs.from_dict("rcll2016", "GameState", data)


def test_from_dict_required_fields():
    partial = {"state": "RUNNING"}
    assert msgs.from_dict("rcll2016", "GameState", partial).state == 2
    with pytest.raises(ValueError, match="game_time"):
        msgs.from_dict("rcll2016", "GameState", partial, require_initialized=True)


def test_from_dict_unknown_message():
    with pytest.raises(KeyError, match="no message 'Nope'"):
        msgs.from_dict("rcll2025", "Nope", {})
