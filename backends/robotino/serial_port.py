"""Opening the Robotino's serial devices with pyserial, and finding the base
by its USB id (Festo 0x1E29, product 0x040D) when no device is given."""
from __future__ import annotations

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


def open_serial(device: str, *, write_timeout: float = 0.2, exclusive: bool = True) -> serial.Serial:
    """Open ``device`` at 115200 8N1, non-blocking reads (select on ``fileno()``)."""
    try:
        return serial.Serial(device, BAUDRATE, bytesize=serial.EIGHTBITS, parity=serial.PARITY_NONE,
                             stopbits=serial.STOPBITS_ONE, timeout=0, write_timeout=write_timeout,
                             exclusive=exclusive)
    except (serial.SerialException, OSError, ValueError) as exc:
        raise BackendUnavailable(f"cannot open serial device {device}: {exc}") from None
