"""Opening the Robotino's serial devices with pyserial, and finding the base
by its USB id (Festo 0x1E29, product 0x040D) when no device is given."""
from __future__ import annotations

import os
import select
import time

import serial
from serial.tools import list_ports

from rll_bt.backend import BackendUnavailable

ROBOTINO_VID = 0x1E29
ROBOTINO_PID = 0x040D
BAUDRATE = 115200

#: exceptions that mean "the link is gone" on read or write
LINK_ERRORS = (serial.SerialException, OSError)


def find_device(vid: int = ROBOTINO_VID, pid: int = ROBOTINO_PID) -> str:
    """The tty of the first USB device with ``vid:pid``."""
    for port in sorted(list_ports.comports(), key=lambda p: p.device):
        if port.vid == vid and port.pid == pid:
            return port.device
    raise BackendUnavailable(
        f"no Robotino base found (no serial device with USB id {vid:04X}:{pid:04X}); "
        "connect it or pass device=/dev/ttyACMx")


#: a device that takes none of a message's bytes for this long (s) is not taking data
WRITE_TIMEOUT = 0.2


def write_all(port: serial.Serial, data: bytes, timeout: float = WRITE_TIMEOUT) -> None:
    """Write all of ``data`` to ``port`` (opened by :func:`open_serial`: non-blocking);
    :class:`serial.SerialTimeoutException` ("Write timeout") only when the device took
    nothing for ``timeout`` seconds.

    pyserial's own ``write`` checks its deadline even after the last byte went out: a
    writer that the machine did not schedule for ``timeout`` (a loaded machine, an
    interpreter lock held elsewhere) got "Write timeout" for a frame written whole, and
    the drivers closed and reopened a link that worked (12 times in a 2-minute hardware
    game whose base emulator never went 0.3 s without reading)."""
    fd = port.fileno()
    view = memoryview(data)
    deadline = time.monotonic() + timeout
    while True:
        try:
            n = os.write(fd, view)
        except BlockingIOError:
            n = 0
        view = view[n:]
        if not view:
            return
        if n:
            deadline = time.monotonic() + timeout        # the device takes data
        _, ready, _ = select.select([], [fd], [], max(deadline - time.monotonic(), 0.0))
        if not ready:
            raise serial.SerialTimeoutException("Write timeout")


def open_serial(device: str, *, write_timeout: float = WRITE_TIMEOUT, exclusive: bool = True) -> serial.Serial:
    """Open ``device`` at 115200 8N1, non-blocking reads (select on ``fileno()``).
    A URL opens through pyserial's URL handlers: ``socket://HOST:PORT`` is a
    device on a TCP port (an Ethernet URG)."""
    try:
        if "://" in device:
            return serial.serial_for_url(device, timeout=0, write_timeout=write_timeout)
        return serial.Serial(device, BAUDRATE, bytesize=serial.EIGHTBITS, parity=serial.PARITY_NONE,
                             stopbits=serial.STOPBITS_ONE, timeout=0, write_timeout=write_timeout,
                             exclusive=exclusive)
    except (serial.SerialException, OSError, ValueError) as exc:
        raise BackendUnavailable(f"cannot open serial device {device}: {exc}") from None
