"""The RCLL gripper's ASCII protocol: commands, checksummed lines, the sketch model."""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.robotino import gripper_protocol as P
from backends.robotino.arduino import GripperFirmware


def test_command_encoding():
    assert P.encode_command([("X", 120), ("Y", 300), ("Z", 0), ("O", 0)]) == b"AT X120 Y300 Z0 O0 +"
    assert P.encode_command([("S", 0)]) == b"AT S0 +"
    with pytest.raises(ValueError):
        P.encode_command([("X", -1)])
    with pytest.raises(ValueError):
        P.encode_command([("W", 1)])


def test_checksums_by_hand():
    # "AT HELLO +": 65+84+32+72+69+76+76+79+32+43 = 628; 628 % 256 = 116
    assert P.hello_line() == b"AT HELLO +116\r\n"
    # "AT I 0 0 0 0 CLOSED+": 181 + 73 + 32 + 4*(48+32) + (67+76+79+83+69+68) + 43 = 1091 -> 67
    assert P.status_line("I", 0, 0, 0, False) == b"AT I 0 0 0 0 CLOSED+67\r\n"
    assert P.FIRMWARE_ERROR_CHECKSUM == 197


def test_status_parsing():
    msg = P.parse_line(P.status_line("M", 12, -300, 4000, True))
    assert msg == P.GripperMessage("status", "M", (12, -300, 4000), 0, True)
    assert P.parse_line(b"AT HELLO +116\r\n") == P.GripperMessage("hello")
    assert P.parse_line(b"noise AT HELLO +116") == P.GripperMessage("hello")


def test_checksum_mismatch_is_rejected():
    line = P.status_line("I", 5, 6, 7, False).replace(b" 5 ", b" 6 ")
    assert isinstance(P.parse_line(line), P.Rejected)
    assert isinstance(P.parse_line(b"AT HELLO +117"), P.Rejected)
    assert isinstance(P.parse_line(b"AT I 0 0 0 0 CLOSED+"), P.Rejected)      # digits cut off
    assert isinstance(P.parse_line(b"gripper open"), P.Rejected)


def test_error_lines_with_the_sketch_checksum_are_accepted():
    msg = P.parse_line(P.error_line("end stop X"))
    assert msg.kind == "status" and msg.state == "E" and msg.text == "end stop X"
    assert isinstance(P.parse_line(b"AT E end stop X+12"), P.Rejected)


def test_line_splitter_handles_chunks():
    s = P.LineSplitter()
    assert s.feed(b"AT HELLO +1") == []
    assert s.feed(b"16\r\nAT I") == [b"AT HELLO +116"]
    assert s.feed(b"\r\n") == [b"AT I"]


def test_steps_per_metre():
    steps = P.StepsPerMetre()
    assert steps.to_steps(0.044, 0.01, 0.0015) == (400, 2000, 400)
    assert steps.to_metres((400, 2000, 400)) == pytest.approx((0.044, 0.01, 0.0015))
    with pytest.raises(ValueError):
        steps.to_steps(-0.001, 0, 0)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120))
def test_line_parser_never_raises(line):
    assert isinstance(P.parse_line(line), (P.GripperMessage, P.Rejected))


@settings(max_examples=200, deadline=None)
@given(st.sampled_from("MI"), st.integers(-99999, 99999), st.integers(-99999, 99999),
       st.integers(-99999, 99999), st.booleans(), st.integers(0, 40), st.integers(0, 255))
def test_corrupting_one_character_is_detected(state, x, y, z, is_open, pos, flip):
    line = P.status_line(state, x, y, z, is_open)[:-2]
    pos %= len(line)
    bad = bytearray(line)
    bad[pos] = (bad[pos] + 1 + flip % 200) % 128 or 1
    if bytes(bad) != line:
        assert isinstance(P.parse_line(bytes(bad)), P.Rejected)


# -- the sketch model -------------------------------------------------------------

def lines(data: bytes) -> list:
    return [P.parse_line(raw) for raw in P.LineSplitter().feed(data)]


def test_power_up_boots_then_says_hello_reports_and_homes():
    fw = GripperFirmware(home_time=0.1, boot_time=0.1)
    assert fw.reset(0.0) == b""                              # the bootloader runs first
    assert fw.receive(b"AT S0 +", 0.05) == b""               # and ignores the sketch's protocol
    out = lines(fw.advance(0.1))
    assert out[0] == P.GripperMessage("hello")
    assert out[1].state == "I" and out[2].state == "M"
    assert lines(fw.advance(0.3))[-1] == P.GripperMessage("status", "I", (0, 0, 0), 0, False)
    assert ("S", 0) not in fw.commands_seen


def test_no_reply_to_moves_but_status_on_change_and_request():
    fw = GripperFirmware(speed=1000.0, home_time=0.0, boot_time=0.0)
    fw.reset(0.0)
    fw.advance(0.01)
    out = lines(fw.receive(b"AT X100 +", 0.02))
    assert [m.state for m in out] == ["M"]                  # the status change, not a receipt
    assert fw.receive(b"AT O0 +", 0.03) == b""               # open: no reply
    assert lines(fw.receive(b"AT S0 +", 0.04))[0].state == "M"
    out = lines(fw.advance(0.2))
    assert out[-1] == P.GripperMessage("status", "I", (100, 0, 0), 0, True)
    assert [m.state for m in lines(fw.receive(b"AT x500 T200 +", 0.3))] == ["I", "I"]
    assert fw.toggle_steps == 200


def test_malformed_number_drops_the_rest_of_the_message():
    fw = GripperFirmware(home_time=0.0, boot_time=0.0)
    fw.reset(0.0)
    fw.advance(0.01)
    assert fw.receive(b"AT Xabc S0 +", 0.02) == b""
    assert fw.target == [0.0, 0.0, 0.0]


def test_error_state_reports_e_lines():
    fw = GripperFirmware(home_time=0.0, boot_time=0.0)
    fw.reset(0.0)
    out = lines(fw.fail("end stop", 0.1))
    assert out[0].state == "E" and out[0].text == "end stop"
    assert lines(fw.receive(b"AT S0 +", 0.2))[0].state == "E"


def test_unicode_digits_in_the_checksum_are_rejected_not_raised():
    # found by benchmarks/fuzz.py: '²'.isdigit() is true, int('²16') raises
    assert isinstance(P.parse_line(b"AT HELLO +\xb216\r\n"), P.Rejected)
