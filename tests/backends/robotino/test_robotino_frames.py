"""Byte-exact framing of the Robotino 3 direct protocol.

Expected bytes are derived by hand from the rules: head 0xAA, uint16 LE
length of the unescaped payload, tags [id][len][data], checksum
(0x10000 - sum(length bytes + payload)) & 0xFFFF as uint16 LE, then 0xAA ->
55 8A and 0x55 -> 55 75 for every byte after the head.
"""
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.robotino import tags as T
from backends.robotino.framing import (
    ChecksumMismatch,
    Frame,
    FrameDecoder,
    FrameError,
    Oversize,
    checksum,
    decode_frame,
    encode_frame,
    stuff,
    unstuff,
)


def frame_of(*tags):
    return encode_frame(T.encode_tags(tags))


def test_set_motor_speed_with_negative_speed():
    # payload 09 03 01 9C FF  (motor 1, -100 = 0xFF9C as int16 LE)
    # sum = 05+00 + 09+03+01+9C+FF = 0x1AD; checksum = 0x10000-0x1AD = 0xFE53 -> 53 FE
    assert frame_of(T.SetMotorSpeed(1, -100)) == bytes.fromhex("AA 0500 09 03 01 9CFF 53FE")


def test_checksum_low_byte_0x55_is_escaped():
    # payload 09 03 00 9A 00 (motor 0, 154 rpm): sum = 5+9+3+0+154+0 = 171 = 0xAB
    # checksum = 0xFF55 -> 55 FF, and 0x55 is sent as 55 75
    assert frame_of(T.SetMotorSpeed(0, 154)) == bytes.fromhex("AA 0500 09 03 00 9A00 5575 FF")


def test_checksum_low_byte_0xaa_is_escaped_with_negative_speed():
    # payload 09 03 00 46 FF (motor 0, -186 = 0xFF46): sum = 5+9+3+0+0x46+0xFF = 0x156
    # checksum = 0xFEAA -> AA FE, and 0xAA is sent as 55 8A
    assert frame_of(T.SetMotorSpeed(0, -186)) == bytes.fromhex("AA 0500 09 03 00 46FF 558A FE")


def test_payload_byte_0xaa_is_escaped():
    # payload 12 01 AA: sum = 3 + 0x12 + 0x01 + 0xAA = 0xC0 -> checksum 0xFF40 -> 40 FF
    assert frame_of(T.SetAllDigitalOutputs(0xAA)) == bytes.fromhex("AA 0300 12 01 558A 40FF")


def test_length_byte_0x55_is_escaped():
    text = "x" * 83                         # tag = 2 + 83 = 85 = 0x55 payload bytes
    frame = frame_of(T.Error(text))
    assert frame[:4] == bytes.fromhex("AA 5575 00")
    assert decode_frame(frame) == bytes([252, 83]) + text.encode()


def test_version_request_as_fawkes_sends_it():
    # payload 01 00 03 00: sum = 4 + 1 + 3 = 8 -> checksum 0xFFF8 -> F8 FF
    assert frame_of(T.GetHwVersion(), T.GetSwVersion()) == bytes.fromhex("AA 0400 0100 0300 F8FF")


def test_stuffing_round_trip_and_helpers():
    data = bytes([0xAA, 0x55, 0x00, 0x8A, 0x75, 0xFF])
    assert stuff(data) == bytes.fromhex("558A 5575 00 8A 75 FF")
    assert unstuff(stuff(data)) == data
    assert checksum(bytes.fromhex("0400 0100 0300")) == 0xFFF8


def test_decode_frame_rejects_bad_frames():
    good = frame_of(T.GetBumper())
    assert decode_frame(good) == bytes([36, 0])
    with pytest.raises(FrameError, match="checksum"):
        decode_frame(good[:-1] + bytes([good[-1] ^ 1]))
    with pytest.raises(FrameError, match="head"):
        decode_frame(good[1:])
    with pytest.raises(FrameError, match="length"):
        decode_frame(bytes.fromhex("AA 0300 2400") + good[-2:])


def test_decoder_reads_a_reply_from_the_base():
    reply = frame_of(T.HwVersion("3.0.0"), T.PowerSourceReadings(24.0, 1.5, 0, 2, 1, 0, 60000),
                     T.PowerButton(0))
    events = FrameDecoder().feed(reply)
    assert len(events) == 1 and isinstance(events[0], Frame)
    tags = T.decode_tags(events[0].payload)
    assert tags[0] == T.HwVersion("3.0.0")
    assert tags[1] == T.PowerSourceReadings(24.0, 1.5, 0, 2, 1, 0, 60000)
    assert tags[2] == T.PowerButton(0)


def test_unescaped_head_restarts_at_the_length_field():
    good = frame_of(T.SetMotorSpeed(2, 500))
    dec = FrameDecoder()
    events = dec.feed(bytes.fromhex("AA 0500 0903") + good)    # a frame cut short by a new head
    assert events == [Frame(T.SetMotorSpeed(2, 500).encode())]
    assert dec.restarts == 1 and dec.checksum_errors == 0


def test_escaped_head_inside_a_frame_is_data():
    dec = FrameDecoder()
    assert dec.feed(frame_of(T.SetAllDigitalOutputs(0xAA))) == [Frame(bytes([18, 1, 0xAA]))]
    assert dec.restarts == 0


def test_oversize_length_is_rejected_then_the_next_frame_is_read():
    dec = FrameDecoder()
    events = dec.feed(bytes.fromhex("AA 0102") + b"\x00" * 20 + frame_of(T.GetBumper()))
    assert events[0] == Oversize(513)
    assert events[1] == Frame(bytes([36, 0]))
    assert dec.oversize == 1


def test_512_byte_payload_is_accepted():
    payload = T.Info("a" * 253).encode() * 2 + bytes([250, 0])
    assert len(payload) == 512
    assert FrameDecoder().feed(encode_frame(payload)) == [Frame(payload)]


def test_checksum_mismatch_is_dropped_and_counted():
    good = bytearray(frame_of(T.SetMotorSpeed(0, 10)))
    good[-2] ^= 0x01
    dec = FrameDecoder()
    events = dec.feed(bytes(good))
    assert isinstance(events[0], ChecksumMismatch)
    assert events[0].computed == checksum(bytes.fromhex("0500 0903000A00"))
    assert events[0].received == events[0].computed ^ 0x01
    assert dec.checksum_errors == 1 and dec.frames == 0


def test_byte_by_byte_feeding_gives_the_same_frames():
    stream = frame_of(T.SetMotorSpeed(0, -186)) + b"\x00\x55" + frame_of(T.SetAllDigitalOutputs(0x55))
    dec = FrameDecoder()
    events = [e for b in stream for e in dec.feed(bytes([b]))]
    assert events == FrameDecoder().feed(stream)
    assert [T.decode_tags(e.payload)[0] for e in events] == [T.SetMotorSpeed(0, -186),
                                                              T.SetAllDigitalOutputs(0x55)]


@settings(max_examples=250, deadline=None)
@given(st.binary(max_size=512))
def test_any_payload_round_trips(payload):
    frame = encode_frame(payload)
    assert 0xAA not in frame[1:]
    assert decode_frame(frame) == payload
    assert FrameDecoder().feed(frame) == [Frame(payload)]


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=600), st.binary(max_size=64))
def test_decoder_survives_garbage_and_resyncs(garbage, payload):
    """No exception, no hang; a frame following garbage and one more frame is read."""
    dec = FrameDecoder()
    dec.feed(garbage)
    frame = encode_frame(payload)
    events = dec.feed(frame + frame)
    assert events[-1] == Frame(payload)
    assert len(events) <= 3


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=300))
def test_tag_decoding_never_raises(payload):
    tags = T.decode_tags(payload)
    assert all(isinstance(t, T.Tag) for t in tags)
    for t in tags:                      # every decoded tag can be sent again
        assert t.encode()[0] == (t.tag_id if isinstance(t, T.RawTag) else t.ID)
