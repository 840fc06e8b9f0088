"""The MJPEG part parser (:class:`backends.devices.camera.mjpeg_reader.PartReader`):
parts however the bytes are cut, with their capture times; nothing it is fed
makes it raise (fuzzed)."""
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.devices.camera.mjpeg_reader import MAX_PART, PartReader, _boundary, part_timestamp

B = b"rllbtframe"


def stream(bodies, stamps):
    out = b""
    for body, t in zip(bodies, stamps):
        out += (b"--" + B + b"\r\nContent-Type: image/jpeg\r\nContent-Length: " + str(len(body)).encode()
                + b"\r\nX-Timestamp: " + f"{t:.6f}".encode() + b"\r\n\r\n" + body + b"\r\n")
    return out


@given(st.lists(st.binary(max_size=300), min_size=1, max_size=6), st.lists(st.integers(1, 97), max_size=40),
       st.data())
@settings(max_examples=200, deadline=None)
def test_parts_come_out_whole_however_the_bytes_are_cut(bodies, cuts, data):
    stamps = [data.draw(st.floats(1e9, 2e9)) for _ in bodies]
    raw = stream(bodies, stamps)
    reader, got, pos = PartReader(B), [], 0
    for c in cuts + [len(raw)]:
        got += reader.feed(raw[pos:pos + c])
        pos += c
    got += reader.feed(raw[pos:])
    assert [b for _h, b in got] == bodies
    assert [part_timestamp(h) for h, _b in got] == [float(f"{t:.6f}") for t in stamps]
    assert reader.bad == 0


@given(st.binary(max_size=2000))
@settings(max_examples=500, deadline=None)
def test_any_bytes_are_taken_without_raising(raw):
    reader = PartReader(B)
    for part in reader.feed(raw) + reader.feed(raw[::-1]):
        assert len(part[1]) <= MAX_PART
        part_timestamp(part[0])


def test_bad_parts_are_skipped_and_counted_and_the_next_one_read():
    raw = (b"--" + B + b"\r\nContent-Length: many\r\n\r\nxx"
           + b"--" + B + b"\r\nContent-Length: 99999999999\r\n\r\n"
           + stream([b"jpeg"], [1.7e9]))
    reader = PartReader(B)
    got = reader.feed(raw)
    assert [b for _h, b in got] == [b"jpeg"] and reader.bad == 2
    assert part_timestamp({"x-timestamp": "nan"}) is None and part_timestamp({}) is None


def test_the_boundary_of_the_content_type():
    assert _boundary("multipart/x-mixed-replace;boundary=rllbtframe") == b"rllbtframe"
    assert _boundary('multipart/x-mixed-replace; boundary="--myboundary"') == b"myboundary"
    assert _boundary("image/jpeg") is None and _boundary("") is None
