"""The emulated lasers read by laser software nobody here wrote, and the
URG driver on an Ethernet URG (SCIP 2.0 on a TCP port).

The peers are PyPI packages written from the vendors' documents by others:
``hokuyolx`` (a SCIP 2.0 client for Hokuyo's Ethernet scanners) and
``sick-scan-tcp`` (a CoLa-A client for SICK scanners).  What they decode
from the emulators must be what the emulated world measured, at the angles
the device's parameters give; a disagreement means one side misreads the
protocol, and ours is the one under test."""
import math
import socket
import time

import numpy as np
import pytest
from hokuyolx import HokuyoLX
from sick_scan_tcp.sick_scan_tcp import SickScan

from backends.devices.laser.tcp_emulators import TimEmulator, UrgTcpEmulator
from backends.devices.laser.tim_device import TIM571, TimDevice
from backends.devices.laser.urg import UrgLaser
from backends.devices.laser.urg_device import UTM_30LX, UrgDevice
from tests.backends.devices.test_devices_urg_link import _ranges as _urg_ranges

TIM_MM = 100.0 + 20.0 * np.arange(811)


@pytest.fixture
def ethernet_urg():
    dev = UrgDevice(UTM_30LX, lambda t: _urg_ranges(UTM_30LX), start=time.monotonic())
    emu = UrgTcpEmulator(dev).start()
    yield dev, emu
    emu.stop()


def test_hokuyolx_reads_the_emulated_ethernet_urg(ethernet_urg):
    dev, emu = ethernet_urg
    m = dev.model
    peer = HokuyoLX(addr=emu.address, tsync=False, convert_time=False, timeout=10)
    try:
        assert (peer.amin, peer.amax, peer.aforw, peer.ares, peer.dmin, peer.dmax) == (
            m.amin, m.amax, m.afrt, m.ares, m.dmin, m.dmax)
        assert peer.scan_freq == m.rpm // 60 and peer.model.startswith("UTM-30LX")
        assert peer.version()["PROT"] == "SCIP 2.0"
        before = (time.monotonic() - dev.boot) * 1000.0
        stamp, dist = peer.get_dist()
        after = (time.monotonic() - dev.boot) * 1000.0
        assert np.array_equal(dist, _urg_ranges(m)[m.amin:m.amax + 1])
        assert np.allclose(peer.get_angles(), m.step_angle(np.arange(m.amin, m.amax + 1)))
        assert before - m.scan_period * 1000.0 - 1 <= stamp <= after + 1     # ms since the sensor booted
        _, part = peer.get_dist(start=100, end=199, grouping=4)             # clusters: the nearest echo
        assert np.array_equal(part, _urg_ranges(m)[100:200].reshape(-1, 4).min(axis=1))
        assert peer.sensor_state()["LASR"] == "ON"
        peer.standby()
        assert peer.sensor_state()["LASR"] == "OFF"
    finally:
        peer.close()


def test_the_urg_driver_reads_an_ethernet_urg_and_survives_its_cable(ethernet_urg, wait_for):
    dev, emu = ethernet_urg
    m = dev.model
    laser = UrgLaser(f"socket://{emu.host}:{emu.port}", timeout=0.5, reopen_interval=0.1).start(wait=120)
    try:
        assert wait_for(lambda: laser.stats().scans >= 3, 3)
        scan = laser.latest()
        assert np.allclose(scan.ranges, _urg_ranges(m)[m.amin:m.amax + 1] / 1000.0)
        assert scan.angle_min == pytest.approx((m.amin - m.afrt) * 2 * math.pi / m.ares)
        # the sensor serves one host: a second connection is closed at once
        with socket.create_connection(emu.address, timeout=5) as other:
            other.settimeout(5)
            assert other.recv(16) == b""
        assert emu.refused == 1 and laser.healthy(0.5)
        emu.unplug(1.0)                                   # the cable out: connection dropped, connects refused
        assert wait_for(lambda: not laser.stats().connected, 2)
        assert wait_for(lambda: laser.healthy(0.3), 5)
        s = laser.stats()
        assert s.link_losses >= 1 and s.connects >= 2 and s.errors == 0
    finally:
        laser.close()


def _cola_a_scan(sock: socket.socket) -> str:
    sock.sendall(b"\x02sRN LMDscandata\x03")
    buf = b""
    while b"\x03" not in buf:
        chunk = sock.recv(65536)
        assert chunk, "the scanner closed the connection"
        buf += chunk
    return buf[:buf.index(b"\x03") + 1].decode("ascii")


def test_sick_scan_tcp_reads_the_emulated_tim():
    emu = TimEmulator(TimDevice(TIM571, lambda t: TIM_MM, start=time.monotonic())).start()
    peer = SickScan(*emu.address)
    try:
        peer.socket_sick.settimeout(10)
        text = SickScan.remove_outprov(_cola_a_scan(peer.socket_sick))
        angles, metres = peer.extract_telegram(text)
        assert np.allclose(metres, TIM_MM / 1000.0)
        assert np.allclose(angles, -45.0 + np.arange(811) * 0.3333)   # the scanner's angles: 90 is ahead
        assert peer.scan().startswith("sRA LMDscandata ")             # its own poll (it sends it twice)
    finally:
        peer.release()
        emu.stop()
