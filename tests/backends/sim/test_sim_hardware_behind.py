"""A world behind the wall clock (a hardware game catching up, games.processes.world_advance): the
laser's cast is stamped with the wall time the world stands at, and a world more than STALE_CAST (0.5 s)
behind casts nothing until it caught up (a scan of it would be stale before it went out)."""
import time

from backends.sim.hardware import WorldHardware
from rll_bt.backend import Pose2D


def test_casts_are_stamped_with_the_time_the_world_stands_at_and_skipped_while_far_behind(make_world):
    world = make_world("rcll2016", seed=3)
    world.add_robot("CYAN", 1, pose=Pose2D(3.0, 2.0, 0.3), laser_noise=0.0)
    hw = WorldHardware(world, laser="urg", camera_fps=1.0, devices="threads")
    rig = hw.add(("CYAN", 1))
    try:
        world.step(0.05)
        behind = time.monotonic() - 0.3                 # behind, less than STALE_CAST
        hw.sync(at=behind)
        assert rig.scans == 1 and rig._cast == behind    # the world's state is of then, and so is its scan
        world.step(0.2)
        far = time.monotonic() - 1.5                     # far behind: catching up first
        hw.sync(at=far)
        assert rig.scans == 1 and rig._cast == behind
        hw.sync()                                        # up to the wall clock: cast at once, stamped now
        assert rig.scans == 2 and behind < rig._cast <= time.monotonic()
    finally:
        hw.stop()
