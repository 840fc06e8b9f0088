"""The URG driver against the emulated sensor on a real pty: scans decode to
the distances the sensor measured, stamps map to host time, and a pulled
cable is survived."""
import math
import time

import numpy as np
import pytest

from backends.devices.laser import LaserMount, scip
from backends.devices.laser.stamps import DeviceClock
from backends.devices.laser.urg import UrgLaser
from backends.devices.laser.urg_device import URG_04LX, UTM_30LX, UrgDevice
from backends.devices.ptyrunner import PtyRunner
from tests.support.scan_stamps import CountingSource, assert_stamps_are_measuring_times, collect_stamps


def _ranges(model):
    steps = np.arange(model.max_step + 1)
    return 500.0 + 10.0 * (steps % 300)          # mm, a different value on every step


@pytest.fixture
def urg(tmp_path):
    made = []

    def make(model=URG_04LX, source=None, device=None):
        dev = device or UrgDevice(model, source or (lambda t: _ranges(model)), start=time.monotonic())
        runner = PtyRunner(dev, str(tmp_path / f"urg{len(made)}")).start()
        made.append(runner)
        return dev, runner
    yield make
    for r in made:
        r.stop()


@pytest.mark.parametrize("mode,encoding", [("stream", 3), ("poll", 3), ("stream", 2)])
def test_scans_decode_to_what_the_sensor_measured(urg, wait_for, mode, encoding):
    dev, runner = urg(UTM_30LX if encoding == 3 else URG_04LX)
    m = dev.model
    laser = UrgLaser(runner.link, mode=mode, encoding=encoding, mount=LaserMount(x=0.1, yaw=0.2)).start(wait=120)
    try:
        assert wait_for(lambda: laser.stats().scans >= 3, 3)
        scan = laser.latest()
        expected = _ranges(m)[m.amin:m.amax + 1] / 1000.0
        if encoding == 2:
            expected = np.where(expected <= 4.095, expected, np.inf)
        assert np.allclose(scan.ranges, expected)
        assert scan.angle_min == pytest.approx((m.amin - m.afrt) * 2 * math.pi / m.ares)
        assert scan.angle_increment == pytest.approx(2 * math.pi / m.ares)
        assert scan.mount.x == 0.1 and scan.mount.theta == 0.2
        assert dev.boot - 0.001 <= scan.stamp <= time.monotonic()          # host time, not device time
        assert laser.info["PROT"] == "SCIP 2.0" and laser.stats().errors == 0
        assert laser.scip11_switches == (1 if m.scip1_at_boot else 0)
    finally:
        laser.close()


def test_stamps_are_the_scan_times_on_the_host_clock(urg):
    """Each scan's stamp is when the sensor measured it, on the host's clock (the measuring moments
    vary against the sensor's sending: tests/support/scan_stamps.py), whatever the machine's load."""
    boot = time.monotonic()
    source = CountingSource(boot, URG_04LX.scan_period, URG_04LX.max_step + 1)
    dev = UrgDevice(URG_04LX, source, start=boot)
    runner = urg(URG_04LX, device=dev)[1]
    laser = UrgLaser(runner.link)
    laser._clock = DeviceClock(1 << 24, 1e-3, window=1 << 20)     # its offset only improves however long it runs
    laser.start(wait=120)
    try:
        assert_stamps_are_measuring_times(collect_stamps(laser, source, 12), source, 12)
    finally:
        laser.close()


def test_an_upside_down_laser_keeps_angles_counter_clockwise(urg):
    dev, runner = urg(UTM_30LX)
    laser = UrgLaser(runner.link, mount=LaserMount(upside_down=True)).start(wait=120)
    try:
        scan = laser.latest()
        m = dev.model
        raw = _ranges(m)[m.amin:m.amax + 1] / 1000.0
        assert np.allclose(scan.ranges, raw[::-1])
        assert scan.angle_min == pytest.approx(-(m.amax - m.afrt) * 2 * math.pi / m.ares)
    finally:
        laser.close()


def test_the_driver_comes_back_after_the_cable_was_pulled(urg, wait_for):
    _dev, runner = urg(URG_04LX)
    laser = UrgLaser(runner.link, timeout=0.5, reopen_interval=0.1).start(wait=120)
    try:
        runner.unplug(1.0)
        assert wait_for(lambda: not laser.stats().connected and not laser.healthy(0.3), 2)
        assert wait_for(lambda: laser.healthy(0.3), 5)
        s = laser.stats()
        assert s.link_losses >= 1 and s.connects >= 2
        assert laser.scip11_switches == 1        # the sensor stayed powered: still SCIP 2.0
    finally:
        laser.close()


def test_a_silent_sensor_is_a_lost_link(urg, wait_for):
    _dev, runner = urg(UTM_30LX)
    laser = UrgLaser(runner.link, timeout=0.4, reopen_interval=0.1).start(wait=120)
    try:
        runner.set_silent(True)
        assert wait_for(lambda: laser.stats().link_losses >= 1, 2)
        runner.set_silent(False)
        assert wait_for(lambda: laser.healthy(0.3), 5)
    finally:
        laser.close()


def test_no_device_is_a_clear_failure(tmp_path):
    with pytest.raises(Exception, match="no scan within"):
        UrgLaser(str(tmp_path / "nothing")).start(wait=0.5)


def test_a_host_that_does_not_read_for_a_while_gets_whole_scans(urg):
    """The host stops reading a running stream for 2 s (an agent busy elsewhere; the pty's buffer holds
    about 1 s of the URG-04LX's scans): the sensor's messages wait, or are dropped whole, never cut, so
    every block the host reads afterwards decodes (a cut scan reached the host as a corrupt data line,
    the laser was lost and the robot stopped)."""
    import serial
    dev, runner = urg(URG_04LX)
    m = dev.model
    port = serial.Serial(runner.link, 115200, timeout=0)
    try:
        port.write(b"SCIP2.0\n" + scip.scan_command("MD", m.amin, m.amax, 1, 0, 0))
        time.sleep(2.0)                                   # not read
        reader, blocks = scip.BlockReader(), []
        end = time.monotonic() + 120.0                    # bounds a hang only
        while time.monotonic() < end and sum(b.command == "MD" and b.status == "99" for b in blocks) < 15:
            blocks += reader.feed(port.read(65536))
            time.sleep(0.01)
    finally:
        port.close()
    scans = [b for b in blocks if b.command == "MD" and b.status == "99"]
    assert len(scans) >= 15                               # what waited, and the stream going on
    stamps = [b.scan(3)[0] for b in scans]                # every one decodes (checksums, length)
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    assert all(len(b.scan(3)[1]) == m.amax - m.amin + 1 for b in scans)
