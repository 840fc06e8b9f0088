"""CoLa-A/CoLa-B framing and the LMDscandata telegram: the field order of
SICK's listing, both dialects round-trip, decoders never crash."""
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.devices.laser import cola
from backends.devices.laser.tim_device import TIM571, TimDevice


def _scan():
    return TimDevice(TIM571, lambda t: np.arange(811) * 10.0 + 60.0).scan(7, 0.5)


def test_the_ascii_scan_telegram_has_the_listings_field_order():
    fields = cola.encode_scan_a("sRA", _scan()).split(b" ")
    assert fields[:2] == [b"sRA", b"LMDscandata"]
    assert fields[2:4] == [b"1", b"1"] and fields[4] == b"12D0A4B"        # version, device, serial
    assert fields[5:7] == [b"0", b"0"]                                    # device status
    assert fields[8] == b"7"                                              # scan counter
    assert fields[11:15] == [b"0", b"0", b"0", b"0"] and fields[15] == b"0"   # inputs, outputs, layer angle
    assert fields[16] == b"5DC" and fields[17] == b"A2"                   # 15 Hz, 16200 beams/s
    assert fields[18:21] == [b"0", b"1", b"DIST1"]
    assert fields[21:26] == [b"3F800000", b"00000000", b"FFF92230", b"D05", b"32B"]
    assert fields[26] == b"3C" and len(fields) == 26 + 811 + 6           # data, then 8-bit channels + footer
    assert fields[-6:] == [b"0"] * 6


def test_both_dialects_round_trip():
    s = _scan()
    a = cola.decode_scan_a(cola.encode_scan_a("sSN", s))
    b = cola.decode_scan_b(cola.encode_scan_b("sSN", s))
    for d in (a, b):
        ch = d.channel("DIST1")
        assert ch.data == s.channels16[0].data and ch.start_angle == -450000 and ch.step == 3333
        assert d.time_since_startup == s.time_since_startup and d.scan_frequency == 1500


def test_frames_and_the_xor_checksum():
    assert cola.frame_a(b"sRN LMDscandata") == b"\x02sRN LMDscandata\x03"
    frame = cola.frame_b(b"sRN LMDscandata")
    assert frame[:8] == b"\x02\x02\x02\x02" + struct.pack(">I", 15)
    assert frame[-1] == 0x05       # XOR of "sRN LMDscandata"
    r = cola.TelegramReader()
    out = r.feed(b"junk" + frame + cola.frame_a(b"sAN SetAccessMode 1") + frame[:-1] + b"\x00")
    assert [(t.payload, t.binary) for t in out] == [(b"sRN LMDscandata", True), (b"sAN SetAccessMode 1", False)]
    assert r.checksum_errors == 1 and r.skipped == 4


def test_error_answers():
    dev = TimDevice(TIM571)
    for binary in (False, True):
        session = dev.session()
        frame = cola.frame_b if binary else cola.frame_a
        session.receive(frame(b"sRN NoSuchVariable") + frame(b"xyz") + frame(b"sMN mSCreboot"), 0.0)
        codes = [cola.error_code(t) for t in cola.TelegramReader().feed(session.take_output())]
        assert codes == [0xB, 0xC, 1]


def test_access_mode_and_streaming_answers():
    s = TimDevice(TIM571, start=0.0).session()
    s.receive(cola.frame_a(b"sMN SetAccessMode 03 F4724744") + cola.frame_a(b"sMN SetAccessMode 03 00000000")
              + cola.frame_a(b"sEN LMDscandata 1"), 0.01)
    s.advance(0.2)
    out = [t.payload for t in cola.TelegramReader().feed(s.take_output())]
    assert out[:3] == [b"sAN SetAccessMode 1", b"sAN SetAccessMode 0", b"sEA LMDscandata 1"]
    assert len(out) == 3 + 3 and all(p.startswith(b"sSN LMDscandata ") for p in out[3:])


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=600))
def test_decoders_never_crash(data):
    for t in cola.TelegramReader().feed(data):
        try:
            (cola.decode_scan_b if t.binary else cola.decode_scan_a)(t.payload)
        except cola.ColaError:
            pass
    for f in (cola.decode_scan_a, cola.decode_scan_b):
        try:
            f(data)
        except cola.ColaError:
            pass


@settings(max_examples=100, deadline=None)
@given(st.binary(max_size=300), st.booleans())
def test_mutated_scan_telegrams_fail_cleanly(noise, binary):
    enc = cola.encode_scan_b if binary else cola.encode_scan_a
    dec = cola.decode_scan_b if binary else cola.decode_scan_a
    good = enc("sSN", _scan())
    cut = len(noise) % len(good)
    try:
        dec(good[:cut] + noise)
    except cola.ColaError:
        pass


@pytest.mark.parametrize("binary", [False, True])
def test_the_device_answers_any_input_without_crashing(binary):
    s = TimDevice(TIM571).session()
    frame = cola.frame_b if binary else cola.frame_a
    for payload in (b"", b"s", b"sEN LMDscandata", b"sEN LMDscandata 7", b"sMN SetAccessMode", b"sWN LMDscandatacfg"):
        s.receive(frame(payload), 0.0)
    assert len(cola.TelegramReader().feed(s.take_output())) == 6


def test_answers_parse_as_the_ros_sick_tim_driver_reads_them():
    """sick_tim reads DeviceIdent with ``sRA 0 6 %6s E V%d.%d`` and checks
    fields 15 ("0") and 20 ("DIST1") and at least 26 + n + 1 + 5 fields."""
    import re
    s = TimDevice(TIM571).session()
    s.receive(cola.frame_a(b"sRI0") + cola.frame_a(b"sRN LMDscandata") + cola.frame_a(b"sRN SCdevicestate"), 0.5)
    ident, scan, state = (t.payload.decode() for t in cola.TelegramReader().feed(s.take_output()))
    assert re.match(r"sRA 0 6 (\S{6}) E V(\d+)\.(\d+)", ident).group(1) == "TiM571"
    fields = scan.split(" ")
    n = int(fields[25], 16)
    assert fields[15] == "0" and fields[20] == "DIST1" and n == 811 and len(fields) >= 26 + n + 1 + 5
    assert state == "sRA SCdevicestate 1"


def test_the_scan_configuration_reads_as_the_listing_gives_it():
    """LMPscancfg: frequency (1/100 Hz), sectors, resolution, start, stop; LMPoutputRange: sectors,
    resolution, start, stop (angles in 1/10000 degree, the TiM571's -45 .. 225 degrees)."""
    for binary in (False, True):
        s = TimDevice(TIM571).session()
        frame = cola.frame_b if binary else cola.frame_a
        s.receive(frame(b"sRN LMPscancfg") + frame(b"sRN LMPoutputRange"), 0.1)
        cfg, out = (t.payload for t in cola.TelegramReader().feed(s.take_output()))
        if binary:
            assert struct.unpack(">IHIii", cfg[len(b"sRA LMPscancfg "):]) == (1500, 1, 3333, -450000, 2249730)
            assert struct.unpack(">HIii", out[len(b"sRA LMPoutputRange "):]) == (1, 3333, -450000, 2249730)
        else:
            assert cfg == b"sRA LMPscancfg 5DC 1 D05 FFF92230 225402"
            assert out == b"sRA LMPoutputRange 1 D05 FFF92230 225402"


def test_a_scan_fed_by_a_world_goes_out_at_its_cast_stamped_with_the_cast_time():
    cast = {"mm": np.zeros(811), "t": -np.inf}
    dev = TimDevice(TIM571, lambda t: (cast["mm"], cast["t"]), start=0.0, on_cast=True)
    s = dev.session()
    s.receive(cola.frame_a(b"sEN LMDscandata 1"), 0.001)
    s.take_output()

    def scans(now):
        s.advance(now)
        return [cola.decode_scan_a(t.payload) for t in cola.TelegramReader().feed(s.take_output())]

    cast.update(mm=np.full(811, 1000.0), t=0.0305)
    (scan,) = scans(0.031)                             # right after the cast, not at the next scan period
    assert scan.time_since_startup == 30500            # stamped when cast (µs), not when sent
    assert set(scan.channel("DIST1").data) == {1000}
    assert scans(0.04) == []                           # that cast is sent once
    cast.update(mm=np.full(811, 2000.0), t=0.05)
    (scan,) = scans(0.09)                              # a late sender keeps the cast's stamp
    assert scan.time_since_startup == 50000 and set(scan.channel("DIST1").data) == {2000}
