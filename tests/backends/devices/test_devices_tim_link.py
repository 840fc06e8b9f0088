"""The TiM driver against the emulated scanner over real TCP sockets."""
import math
import time

import numpy as np
import pytest

from backends.devices.laser import LaserMount
from backends.devices.laser.tim import TimLaser
from backends.devices.laser.tim_device import TIM571, TimDevice
from backends.devices.laser.tim_emulator import TimEmulator

MM = 100.0 + 20.0 * np.arange(811)


@pytest.fixture
def tim():
    emu = TimEmulator(TimDevice(TIM571, lambda t: MM, start=time.monotonic())).start()
    yield emu
    emu.stop()


@pytest.mark.parametrize("dialect,mode", [("a", "stream"), ("b", "stream"), ("a", "poll"), ("b", "poll")])
def test_scans_decode_to_what_the_scanner_measured(tim, wait_for, dialect, mode):
    laser = TimLaser(*tim.address, dialect=dialect, mode=mode, mount=LaserMount(x=0.2)).start(wait=5)
    try:
        assert wait_for(lambda: laser.stats().scans >= 3, 3)
        scan = laser.latest()
        expected = np.where(MM / 1000.0 <= 25.0, MM / 1000.0, np.inf)
        assert np.allclose(scan.ranges, expected)
        assert scan.angle_min == pytest.approx(math.radians(-135.0))
        assert scan.angle_increment == pytest.approx(math.radians(0.3333))
        assert abs(scan.stamp - time.monotonic()) < 0.5 and scan.mount.x == 0.2
        assert laser.access_granted and laser.info["DeviceIdent"].startswith("TiM571")
        assert laser.stats().errors == 0
    finally:
        laser.close()


def test_stamps_follow_the_scan_frequency(tim):
    laser = TimLaser(*tim.address).start(wait=5)
    try:
        seen = []
        end = time.monotonic() + 1.2
        while time.monotonic() < end:
            s = laser.latest()
            if s is not None and (not seen or s.stamp != seen[-1]):
                seen.append(s.stamp)
            time.sleep(0.003)
        assert len(seen) >= 10
        assert np.allclose(np.diff(seen), 1 / 15, atol=0.02)
    finally:
        laser.close()


def test_the_driver_comes_back_after_the_cable_was_pulled(tim, wait_for):
    laser = TimLaser(*tim.address, timeout=0.5, reopen_interval=0.1).start(wait=5)
    try:
        tim.unplug(1.0)
        assert wait_for(lambda: not laser.stats().connected, 2)
        assert wait_for(lambda: laser.healthy(0.3), 5)
        assert laser.stats().link_losses >= 1 and tim.connects >= 2
    finally:
        laser.close()
