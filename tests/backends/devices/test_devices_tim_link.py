"""The TiM driver against the emulated scanner over real TCP sockets."""
import math
import time

import numpy as np
import pytest

from backends.devices.laser import LaserMount
from backends.devices.laser.stamps import DeviceClock
from backends.devices.laser.tcp_emulators import TimEmulator
from backends.devices.laser.tim import TimLaser
from backends.devices.laser.tim_device import TIM571, TimDevice
from tests.support.scan_stamps import CountingSource, assert_stamps_are_measuring_times, collect_stamps

MM = 100.0 + 20.0 * np.arange(811)


@pytest.fixture
def tim():
    emu = TimEmulator(TimDevice(TIM571, lambda t: MM, start=time.monotonic())).start()
    yield emu
    emu.stop()


@pytest.mark.parametrize("dialect,mode", [("a", "stream"), ("b", "stream"), ("a", "poll"), ("b", "poll")])
def test_scans_decode_to_what_the_scanner_measured(tim, wait_for, dialect, mode):
    laser = TimLaser(*tim.address, dialect=dialect, mode=mode, mount=LaserMount(x=0.2)).start(wait=120)
    try:
        assert wait_for(lambda: laser.stats().scans >= 3, 3)
        scan = laser.latest()
        expected = np.where(MM / 1000.0 <= 25.0, MM / 1000.0, np.inf)
        assert np.allclose(scan.ranges, expected)
        assert scan.angle_min == pytest.approx(math.radians(-135.0))
        assert scan.angle_increment == pytest.approx(math.radians(0.3333))
        assert tim.device.boot - 0.001 <= scan.stamp <= time.monotonic() and scan.mount.x == 0.2   # host time
        assert laser.access_granted and laser.info["DeviceIdent"].startswith("TiM571")
        assert laser.stats().errors == 0
    finally:
        laser.close()


def test_stamps_are_the_scan_times_on_the_host_clock():
    """Each scan's stamp is when the scanner measured it, on the host's clock (the measuring moments
    vary against the scanner's sending: tests/support/scan_stamps.py), whatever the machine's load."""
    boot = time.monotonic()
    source = CountingSource(boot, TIM571.scan_period, TIM571.count)
    emu = TimEmulator(TimDevice(TIM571, source, start=boot)).start()
    laser = TimLaser(*emu.address)
    laser._clock = DeviceClock(1 << 32, 1e-6, window=1 << 20)     # its offset only improves however long it runs
    try:
        laser.start(wait=120)
        assert_stamps_are_measuring_times(collect_stamps(laser, source, 12), source, 12)
    finally:
        laser.close()
        emu.stop()


def test_the_driver_comes_back_after_the_cable_was_pulled(tim, wait_for):
    laser = TimLaser(*tim.address, timeout=0.5, reopen_interval=0.1).start(wait=120)
    try:
        tim.unplug(1.0)
        assert wait_for(lambda: not laser.stats().connected and not laser.healthy(0.3), 2)
        assert wait_for(lambda: laser.healthy(0.3), 5)
        assert laser.stats().link_losses >= 1 and tim.connects >= 2
    finally:
        laser.close()
