"""The command codec of both wires: the refbox's payloads and register
writes decode to the right command, every command survives a round trip,
and anything else is a CommandError (hypothesis)."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.sim.mps.commands import Command, CommandError, from_opcua, parse_mqtt


@pytest.mark.parametrize("payload, command", [
    ("RESET", Command("RESET")),
    ("LIGHT YELLOW BLINK", Command("LIGHT", ("YELLOW", "BLINK"))),
    ("MOVE_CONVEYOR TO_INPUT IN", Command("MOVE_CONVEYOR", ("TO_INPUT", "IN"))),
    ("GET_BASE SILVER", Command("GET_BASE", ("SILVER",))),
    ("CAP_ACTION MOUNT", Command("CAP_ACTION", ("MOUNT",))),
    ("MOUNT_RING RING2", Command("MOUNT_RING", (2, None))),
    ("DELIVER SLOT3", Command("DELIVER", (3,))),
    ("RETRIEVE 5,7", Command("RETRIEVE", ((5, 7),))),
    ("RELOCATE 0,1 0,3", Command("RELOCATE", ((0, 1), (0, 3)))),
])
def test_the_refbox_payloads(payload, command):
    assert parse_mqtt(payload) == command
    assert parse_mqtt(payload.encode()) == command


@pytest.mark.parametrize("kind, write, command", [
    ("BS", (101, 3, 0), Command("GET_BASE", ("BLACK",))),
    ("BS", (102, 1, 2), Command("MOVE_CONVEYOR", ("TO_INPUT", "IN"))),
    ("CS", (301, 1, 0), Command("CAP_ACTION", ("RETRIEVE",))),
    ("RS", (203, 1, 4), Command("MOUNT_RING", (1, "RING_YELLOW"))),
    ("DS", (401, 2, 0), Command("DELIVER", (2,))),
    ("SS", (550, 1, 23), Command("RELOCATE", ((0, 1), (2, 3)))),
    ("SS", (500, 0, 0), Command("RESET")),
    ("CS", (22, 1, 0), Command("LIGHT", ("YELLOW", "ON"))),
    ("RS", (10, 2, 0), Command("SET_TYPE", ("RS",))),
])
def test_the_refbox_register_writes(kind, write, command):
    assert from_opcua(kind, *write) == command


@pytest.mark.parametrize("payload", ["", "LIGHT RED", "LIGHT RED ON EXTRA", "GET_BASE GREEN", "DELIVER SLOT4",
                                     "RETRIEVE 6,0", "RETRIEVE 0,8", "RETRIEVE a,b", "reset", "RESET ",
                                     "MOVE_CONVEYOR TO_OUTPUT", b"\xff\xfe"])
def test_what_is_no_command_is_refused(payload):
    with pytest.raises(CommandError):
        parse_mqtt(payload)


COMMANDS = st.one_of(
    st.just(Command("RESET")),
    st.builds(lambda c, s: Command("LIGHT", (c, s)), st.sampled_from(["RED", "YELLOW", "GREEN"]),
              st.sampled_from(["OFF", "ON", "BLINK"])),
    st.builds(lambda d, t: Command("MOVE_CONVEYOR", (d, t)), st.sampled_from(["TO_OUTPUT", "TO_INPUT"]),
              st.sampled_from(["IN", "MID", "OUT"])),
    st.builds(lambda s: Command("DELIVER", (s,)), st.integers(1, 3)),
    st.builds(lambda a, s, lo: Command(a, ((s, lo),)), st.sampled_from(["RETRIEVE", "STORE"]),
              st.integers(0, 5), st.integers(0, 7)),
)


@given(COMMANDS)
def test_every_command_survives_both_wires(cmd):
    assert parse_mqtt(cmd.mqtt()) == cmd
    kind = "SS" if cmd.action in ("RETRIEVE", "STORE") else "DS"
    _, action, d0, d1 = cmd.opcua(kind)
    assert from_opcua(kind, action, d0, d1) == cmd


@settings(max_examples=300)
@given(st.binary(max_size=60))
def test_random_payloads_are_commands_or_refused(data):
    try:
        assert isinstance(parse_mqtt(data), Command)
    except CommandError:
        pass


@settings(max_examples=300)
@given(st.sampled_from(["BS", "RS", "CS", "DS", "SS"]), st.integers(0, 65535), st.integers(0, 65535),
       st.integers(0, 65535))
def test_random_register_writes_are_commands_or_refused(kind, action, d0, d1):
    try:
        assert isinstance(from_opcua(kind, action, d0, d1), Command)
    except CommandError:
        pass
