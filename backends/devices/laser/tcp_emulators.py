"""The lasers that sit on Ethernet, served on a TCP port of loopback
(:class:`~backends.devices.tcp_server.DeviceServer`):

* :class:`TimEmulator`: a SICK TiM5xx (CoLa on port 2112 on the real one);
  every client gets its own session;
* :class:`UrgTcpEmulator`: an Ethernet Hokuyo (UTM-30LX-EW, UST-10LX/20LX:
  SCIP 2.0 on port 10940 on the real ones), one client at a time; a new
  connection starts from a quiet link (no stream running), the laser's
  state (on or off) is kept as the device keeps it.

    emu = TimEmulator(TimDevice(TIM571, source)).start()
    emu.address        # ("127.0.0.1", port) for the driver
"""
from __future__ import annotations

from ..tcp_server import DeviceServer
from .tim_device import TimDevice
from .urg_device import UrgDevice


class TimEmulator(DeviceServer):
    name = "TiM"

    def __init__(self, device: TimDevice, **options):
        super().__init__(device.session, **options)
        self.device = device


class UrgTcpEmulator(DeviceServer):
    name = "URG"

    def __init__(self, device: UrgDevice, **options):
        super().__init__(device.new_link, max_clients=1, **options)
        self.device = device
