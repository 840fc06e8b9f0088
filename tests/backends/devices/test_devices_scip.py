"""SCIP 2.0 codec and the URG device model: the bytes the vendor's
specification shows, and decoders that never crash on garbage."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.devices.laser import scip
from backends.devices.laser.urg_device import URG_04LX, UTM_30LX, UrgDevice


def _blocks(dev, text, now=1.0):
    dev.receive(text, now)
    return scip.BlockReader().feed(dev.take_output())


def test_checksums_and_encodings_are_those_of_the_specification():
    assert scip.status_line("00") == b"00P\n" and scip.status_line("99") == b"99b\n"
    assert scip.info_line("DMIN", "20") == b"DMIN:20;4\n"           # the spec's PP example
    assert scip.info_line("SCAN", "600") == b"SCAN:600;e\n"
    assert scip.info_line("VEND", "Hokuyo Automatic Co.,Ltd.") == b"VEND:Hokuyo Automatic Co.,Ltd.;[\n"
    assert scip.encode(16_000_000, 4) == b"m2@0"                    # the spec's 4-character example
    assert scip.decode(b"m2@0") == 16_000_000
    assert scip.encode(5432, 3) == b"1Dh" and scip.encode(1234, 2) == b"CB"


def test_pp_of_an_urg_04lx_is_the_example_of_the_specification():
    dev = UrgDevice(URG_04LX)
    dev.scip2 = True
    dev.receive(b"PP\n", 0.0)
    out = dev.take_output()
    assert out.startswith(b"PP\n00P\nMODL:URG-04LX-UG01(Hokuyo Automatic Co.,Ltd.);")
    assert b"\nDMIN:20;4\nDMAX:5600;_\nARES:1024;\\\nAMIN:44;7\nAMAX:725;o\nAFRT:384;6\nSCAN:600;e\n\n" in out
    assert out.endswith(b"\n\n")


def test_an_urg_04lx_starts_in_scip_1_1_and_switches():
    dev = UrgDevice(URG_04LX)
    assert _blocks(dev, b"QT\n")[0].lines == [b"E"]
    dev.receive(b"SCIP2.0\n", 0.1)
    assert dev.take_output() == b"SCIP2.0\n0\n\n"
    assert _blocks(dev, b"QT\n")[0].status == "00"


def test_error_statuses():
    dev = UrgDevice(UTM_30LX)
    assert _blocks(dev, b"GD0000108001\n")[0].status == "10"          # laser off
    assert _blocks(dev, b"GDx000108001\n")[0].status == "01"
    assert _blocks(dev, b"GD0000x08001\n")[0].status == "02"
    assert _blocks(dev, b"GD00001080x1\n")[0].status == "03"
    assert _blocks(dev, b"GD0000200001\n")[0].status == "04"          # beyond the last step
    assert _blocks(dev, b"GD0100005001\n")[0].status == "05"
    assert _blocks(dev, b"MD0000108001x00\n")[0].status == "06"
    assert _blocks(dev, b"MD00001080010x0\n")[0].status == "07"
    assert _blocks(dev, b"GD000010\n")[0].status == "0C"
    assert _blocks(dev, b"XX\n")[0].status == "0E"
    assert _blocks(dev, b"BM;abcdefghijklmnopq\n")[0].status == "0G"
    assert _blocks(dev, b"BM;a#b\n")[0].status == "0H"
    assert _blocks(dev, b"BM\n")[0].status == "00"
    assert _blocks(dev, b"BM\n")[0].status == "02"                     # already on
    assert dev.errors_sent == 13


def test_md_acknowledges_then_streams_with_remaining_count_and_its_string():
    dev = UrgDevice(UTM_30LX, lambda t: np.full(1081, 2000.0), start=0.0)
    dev.receive(b"MD0000108001002;hi\n", 0.001)
    ack = scip.BlockReader().feed(dev.take_output())
    assert ack[0].echo == b"MD0000108001002;hi" and ack[0].lines == [b"00P"]
    dev.advance(0.2)
    scans = scip.BlockReader().feed(dev.take_output())
    assert [b.echo for b in scans] == [b"MD0000108001001;hi", b"MD0000108001000;hi"]
    assert all(b.status == "99" for b in scans)
    stamp, values = scans[0].scan(3)
    assert stamp == 25 and values == [2000] * 1081                    # the first scan after the command
    assert not dev.laser_on and dev.stream is None                    # a finite MD switches the laser off


def test_clusters_take_the_smallest_valid_value_and_errors_stay_below_dmin():
    ranges = np.full(769, 3000.0)
    ranges[100] = 1500.0
    ranges[101] = np.nan
    dev = UrgDevice(URG_04LX, lambda t: ranges)
    values = dev.measure(0.0, 40, 110, 3, 3)
    assert values[0] == 1                                  # steps 40..42 lie outside AMIN..AMAX
    assert values[(100 - 40) // 3] == 1500
    assert all(v in (1, 1500, 3000) for v in values)
    assert dev.measure(0.0, 384, 384, 1, 2) == [3000]      # fits 12 bits
    ranges[384] = 5000.0
    assert dev.measure(0.0, 384, 384, 1, 2) == [1]         # does not: an error code


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=400))
def test_the_block_reader_and_block_decoders_never_crash(data):
    for block in scip.BlockReader().feed(data):
        for call in (lambda b=block: b.status, block.info, lambda b=block: b.scan(3), lambda b=block: b.scan(2)):
            try:
                call()
            except scip.ScipError:
                pass


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(0, (1 << 18) - 1), min_size=1, max_size=300), st.sampled_from([2, 3]))
def test_values_survive_a_data_block(values, size):
    values = [v & ((1 << (6 * size)) - 1) for v in values]
    body = scip.sum_line(scip.encode(123456, 4)) + scip.data_block(scip.encode_values(values, size)) + b"\n"
    (block,) = scip.BlockReader().feed(b"MD0000000001000\n99b\n" + body)
    assert block.scan(size) == (123456, values)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-5, (1 << 24) + 5), max_size=80), st.sampled_from([2, 3, 4]))
def test_a_whole_scan_encodes_and_decodes_as_its_values_one_by_one(values, size):
    fits = all(0 <= v < 1 << (6 * size) for v in values)
    if not fits:
        with pytest.raises(ValueError):
            scip.encode_values(values, size)
        return
    data = scip.encode_values(values, size)
    assert data == b"".join(scip.encode(v, size) for v in values)
    assert scip.decode_values(data, size) == [scip.decode(data[i:i + size]) for i in range(0, len(data), size)]


def test_a_character_outside_the_scip_digits_is_named():
    with pytest.raises(scip.ScipError, match="'~' is not a SCIP digit"):
        scip.decode_values(b"0~", 2)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=200))
def test_the_device_answers_any_input_without_crashing(data):
    dev = UrgDevice(UTM_30LX)
    dev.receive(data, 0.5)
    dev.advance(1.0)
    for block in scip.BlockReader().feed(dev.take_output()):
        assert block.lines, "every reply has a status"


def test_replies_have_the_line_counts_the_vendors_library_checks():
    """urg_library counts the lines of VV (7), PP (10) and II (9) replies,
    echo and status included, the empty line not; and a switched URG-04LX
    answers its first QT with status 00."""
    dev = UrgDevice(URG_04LX)
    assert _blocks(dev, b"QT\n")[0].lines == [b"E"]
    dev.receive(b"SCIP2.0\n", 0.0)
    dev.take_output()
    for cmd, lines in ((b"VV\n", 7), (b"PP\n", 10), (b"II\n", 9)):
        (block,) = _blocks(dev, cmd)
        assert 1 + len(block.lines) == lines, cmd
        assert block.status == "00"
        block.info()                      # every line's checksum right
    (ss,) = _blocks(dev, b"SS115200\n")
    assert ss.status == "03"              # already at that bit rate: one of the statuses the library accepts


class _World:
    """A world that casts a laser's ranges at moments of its own: ``source(t)`` gives
    the newest cast and the device time it was cast at (``-inf``: none yet)."""

    def __init__(self, size):
        self.size, self.ranges, self.taken = size, np.zeros(size), -np.inf

    def cast(self, value, t):
        self.ranges, self.taken = np.full(self.size, float(value)), t

    def source(self, t):
        return self.ranges, self.taken


def test_a_scan_fed_by_a_world_goes_out_at_its_cast_stamped_with_the_cast_time():
    world = _World(769)
    dev = UrgDevice(URG_04LX, world.source, start=0.0, on_cast=True)
    dev.receive(b"SCIP2.0\nMD0044072501000\n", 0.001)
    dev.take_output()
    dev.advance(0.05)
    assert dev.take_output() == b""                   # nothing cast yet, none due
    world.cast(1000, 0.130)
    dev.advance(0.131)                                 # right after the cast, not at the next scan period (0.2)
    (scan,) = scip.BlockReader().feed(dev.take_output())
    stamp, values = scan.scan(3)
    assert stamp == 130 and set(values) == {1000}      # stamped when cast, not when sent
    dev.advance(0.14)
    assert dev.take_output() == b""                   # that cast is sent once
    world.cast(1500, 0.150)
    dev.advance(0.190)                                 # a late sender keeps the cast's stamp
    (scan,) = scip.BlockReader().feed(dev.take_output())
    assert scan.scan(3)[0] == 150 and set(scan.scan(3)[1]) == {1500}
    dev.advance(0.3)
    assert dev.take_output() == b""
    dev.advance(0.4)                                   # no cast for two scan periods: the newest again, its own stamp
    (scan,) = scip.BlockReader().feed(dev.take_output())
    assert scan.scan(3)[0] == 150
