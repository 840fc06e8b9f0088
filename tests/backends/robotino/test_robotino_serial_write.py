"""Writing to a serial device (a real pty): a frame the device takes goes out
whole whatever the writer's own delays; "Write timeout" only for a device that
takes nothing."""
import os
import tty

import pytest
import serial

from backends.robotino.serial_port import open_serial, write_all


@pytest.fixture
def line():
    """(the device's end of a pty, the host's port on the other)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    os.set_blocking(master, False)
    port = open_serial(os.ttyname(slave), exclusive=False)
    yield master, port
    port.close()
    os.close(slave)
    os.close(master)


def read_all(fd):
    out = b""
    while True:
        try:
            chunk = os.read(fd, 65536)
        except BlockingIOError:
            return out
        out += chunk


def test_a_frame_the_device_takes_is_written_whatever_the_writers_delay(line):
    master, port = line
    frame = bytes(range(200))
    # a writer that reaches its deadline check late (here: a deadline already passed) while the device
    # has room: pyserial's own write calls that a timeout, after writing the frame
    port.write_timeout = 1e-9
    with pytest.raises(serial.SerialTimeoutException):
        port.write(frame)
    assert read_all(master) == frame
    write_all(port, frame, timeout=0.0)            # the frame goes out, no timeout
    assert read_all(master) == frame


def test_a_device_that_takes_nothing_is_a_write_timeout(line):
    master, port = line
    with pytest.raises(serial.SerialTimeoutException):
        for _ in range(10_000):                     # the device never reads: its buffer fills
            write_all(port, b"x" * 1024, timeout=0.2)
