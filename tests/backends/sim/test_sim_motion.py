import math

import pytest

from backends.robotino.kinematics import OmniKinematics
from backends.sim import SimBackend
from rll_bt.backend import Pose2D, open_backend
from rll_bt.rules import ROBOT


def _drive_pattern(world, bots, seconds=3.0):
    """Drive every robot with a fixed command pattern; record poses, odometry, scans."""
    log = []
    steps = int(seconds / 0.1)
    for k in range(steps):
        for i, b in enumerate(bots):
            b.drive(0.6, 0.15 * math.sin(0.3 * k + i), 0.4 * math.cos(0.2 * k))
        world.step(0.1)
        for b in bots:
            r = b.robot
            log.append((r.pose.x, r.pose.y, r.pose.theta, *b.odometry().pose.__dict__.values()))
        if k % 5 == 0:
            log.extend(tuple(b.laser_scan().ranges) for b in bots)
    return log


def test_same_seed_same_commands_same_trajectories(make_world):
    runs = []
    for _ in range(2):
        w = make_world("rcll2016", seed=11)
        bots = [SimBackend(w, ("CYAN", n)) for n in (1, 2, 3)]   # odometry and laser noise on
        runs.append(_drive_pattern(w, bots))
    assert runs[0] == runs[1]
    w = make_world("rcll2016", seed=12)
    other = _drive_pattern(w, [SimBackend(w, ("CYAN", n)) for n in (1, 2, 3)])
    assert other != runs[0]          # noise depends on the seed


def test_speed_and_acceleration_limits(empty_world):
    world = empty_world
    bot = SimBackend(world, ("CYAN", 1), pose=Pose2D(-4.0, 1.0, 0.0), wheel_rpm_max=None)
    bot.drive(3.0, 0.0, 0.0)
    world.step(0.1)
    v = bot.odometry().vx
    assert v == pytest.approx(ROBOT.max_accel * 0.1, rel=0.05)
    for _ in range(20):
        bot.drive(3.0, 0.0, 0.0)
        world.step(0.1)
    assert bot.odometry().vx == pytest.approx(ROBOT.max_speed)
    # diagonal commands are clipped as a vector
    for _ in range(10):
        bot.drive(1.0, 1.0, 0.0)
        world.step(0.1)
    o = bot.odometry()
    assert math.hypot(o.vx, o.vy) == pytest.approx(ROBOT.max_speed, abs=1e-6)


def _settled(bot, world, command, seconds=3.0):
    for _ in range(int(seconds / 0.1)):
        bot.drive(*command)
        world.step(0.1)
    o = bot.odometry()
    return o.vx, o.vy, o.omega


def test_the_wheels_limit_the_speed_as_on_the_robotino(empty_world):
    """Each motor turns at most 3000 rpm: 0.7 m/s straight ahead is 0.68, a
    turn while driving takes its share of the same wheels, and the robot
    drives the commanded curve slower, as the robotino backend's host sends it."""
    kin = OmniKinematics()
    bot = SimBackend(empty_world, ("CYAN", 1), pose=Pose2D(-4.0, 1.0, 0.0),
                     odom_noise_trans=0.0, odom_noise_rot=0.0, wheel_rpm_max=3000.0)
    ahead = _settled(bot, empty_world, (0.7, 0.0, 0.0))
    assert ahead[0] == pytest.approx(3000.0 / (kin.k * math.sqrt(3) / 2), rel=1e-3) and ahead[0] < 0.69
    turning = _settled(bot, empty_world, (0.7, 0.0, 1.6))
    assert math.hypot(turning[0], turning[1]) < 0.6 and turning[2] < 1.6
    assert turning[2] / turning[0] == pytest.approx(1.6 / 0.7, rel=1e-3) and abs(turning[1]) < 1e-6
    assert max(abs(m) for m in kin.forward(*turning)) == pytest.approx(3000.0, rel=1e-3)
    assert turning == pytest.approx(kin.clamped(0.7, 0.0, 1.6), abs=1e-3)     # what the robotino backend sends
    slow = _settled(bot, empty_world, (0.3, 0.1, 0.5))                          # within reach: as commanded
    assert slow == pytest.approx((0.3, 0.1, 0.5), abs=1e-6)


def test_deadman_drops_a_stale_command(world):
    bot = SimBackend(world, ("CYAN", 1), odom_noise_trans=0.0, odom_noise_rot=0.0)
    bot.drive(0.4, 0.0, 0.0)
    world.step(0.4)
    assert bot.odometry().vx > 0.3
    world.step(1.0)               # no new command: dropped after 0.5 s, the robot brakes
    assert bot.odometry().vx == 0.0
    y = world.robot_pose("CYAN", 1).y
    world.step(1.0)
    assert world.robot_pose("CYAN", 1).y == y


def test_odometry_frames_and_noise_free_dead_reckoning(make_world):
    w = make_world("rcll2016", seed=2)
    zero = SimBackend(w, ("CYAN", 1), odom_noise_trans=0.0, odom_noise_rot=0.0)
    field = SimBackend(w, ("CYAN", 2), odom_noise_trans=0.0, odom_noise_rot=0.0, odom_frame="field")
    start1, start2 = w.robot_pose("CYAN", 1), w.robot_pose("CYAN", 2)
    assert zero.odometry().pose == Pose2D()
    assert field.odometry().pose == start2
    for _ in range(20):
        zero.drive(0.5, 0.1, 0.3)
        field.drive(0.5, 0.1, 0.3)
        w.step(0.1)
    truth1 = w.robot_pose("CYAN", 1).relative_to(start1)
    o = zero.odometry().pose
    assert (o.x, o.y, o.theta) == pytest.approx((truth1.x, truth1.y, truth1.theta), abs=1e-9)
    t2, o2 = w.robot_pose("CYAN", 2), field.odometry().pose
    assert (o2.x, o2.y, o2.theta) == pytest.approx((t2.x, t2.y, t2.theta), abs=1e-9)


def test_odometry_drifts_with_noise(make_world):
    w = make_world("rcll2016", seed=2)
    bot = SimBackend(w, ("CYAN", 1), odom_noise_trans=0.05, odom_noise_rot=0.05)
    start = w.robot_pose("CYAN", 1)
    for _ in range(30):
        bot.drive(0.5, 0.0, 0.0)
        w.step(0.1)
    truth = w.robot_pose("CYAN", 1).relative_to(start)
    o = bot.odometry().pose
    err = math.hypot(o.x - truth.x, o.y - truth.y)
    assert 1e-4 < err < 0.5


def _wall_test_pose(world):
    """A cyan robot in the field, 0.5 m below the far wall, facing it."""
    f = world.profile.field
    return Pose2D(0.0, f.y_max - 0.5, math.pi / 2)


def test_driving_into_a_wall_is_blocked_and_counted(empty_world):
    world = empty_world
    bot = SimBackend(world, ("CYAN", 1), pose=_wall_test_pose(world))
    assert world.collision_count == 0
    for _ in range(30):
        bot.drive(0.5, 0.0, 0.0)
        world.step(0.1)
    r = bot.robot
    assert r.collisions == 1 and world.collision_count == 1
    assert world.collision_log[0].obstacle == "wall"
    assert r.blocked_steps > 1
    assert -1e-9 <= world.clearance("CYAN", 1) < 0.02     # stopped at the wall, not inside
    assert bot.bumper()
    assert bot.odometry().vx == 0.0
    for _ in range(10):                                    # backing off is allowed
        bot.drive(-0.3, 0.0, 0.0)
        world.step(0.1)
    assert world.clearance("CYAN", 1) > 0.1
    assert not bot.bumper()
    for _ in range(20):                                    # a second push is a second collision
        bot.drive(0.5, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_count == 2


def test_robots_and_stations_block_robots(world):
    st = world.station("C-BS")
    pose = st.approach_pose("input", gap=0.3)
    a = SimBackend(world, ("CYAN", 1), pose=pose)
    for _ in range(20):
        a.drive(0.4, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_log[-1].obstacle == "C-BS"
    p = world.robot_pose("CYAN", 1)
    assert st.box.sdf(p.x, p.y) >= ROBOT.radius - 1e-9
    # a robot in the way of another
    # two robots in the magenta insertion area, one driving into the other
    b = SimBackend(world, ("MAGENTA", 1), pose=Pose2D(-5.5, -0.5, 0.0))
    c = SimBackend(world, ("MAGENTA", 2), pose=Pose2D(-4.3, -0.5, 0.0))
    for _ in range(20):
        b.drive(0.5, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_log[-1].obstacle == "robot MAGENTA/2"
    pb, pc = world.robot_pose("MAGENTA", 1), world.robot_pose("MAGENTA", 2)
    assert math.hypot(pb.x - pc.x, pb.y - pc.y) >= 2 * ROBOT.radius - 1e-9
    assert b.bumper() and c.bumper()


def test_two_robots_driving_into_each_other_are_one_collision(world):
    """Whichever of two robots pushes first, or both, while they touch: one
    contact is one collision (of the first to run into the other); apart
    again and back, a second."""
    a = SimBackend(world, ("CYAN", 1), pose=Pose2D(-5.5, -0.5, 0.0))
    b = SimBackend(world, ("MAGENTA", 1), pose=Pose2D(-4.5, -0.5, math.pi))
    for _ in range(30):
        a.drive(0.4, 0.0, 0.0)
        b.drive(0.4, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_count == 1 and len(world.collision_log) == 1
    for _ in range(10):                       # one stands, the other pushes on
        a.drive(0.2, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_count == 1
    for _ in range(10):                       # apart ...
        a.drive(-0.3, 0.0, 0.0)
        b.drive(-0.3, 0.0, 0.0)
        world.step(0.1)
    for _ in range(30):                       # ... and together again
        a.drive(0.3, 0.0, 0.0)
        world.step(0.1)
    assert world.collision_count == 2


def test_open_backend_entry_point_and_options(world):
    bot = open_backend("sim", world=world, robot=("MAGENTA", 2), laser_beams=90)
    assert isinstance(bot, SimBackend)
    assert world.robot("MAGENTA", 2).config.laser_beams == 90
    assert len(bot.laser_scan().ranges) == 90
    again = open_backend("sim", world=world, robot=("MAGENTA", 2))
    assert again.robot is bot.robot
    with pytest.raises(ValueError, match="already in the world"):
        open_backend("sim", world=world, robot=("MAGENTA", 2), laser_beams=10)
    with pytest.raises(TypeError, match="unknown sim robot option"):
        open_backend("sim", world=world, robot=3, lasr_beams=10)
    with pytest.raises(ValueError, match="finite"):
        bot.drive(float("nan"), 0, 0)


def test_battery_drains(world):
    bot = SimBackend(world, ("CYAN", 1), battery_life=100.0)
    full = bot.battery()
    world.step(50.0)
    half = bot.battery()
    assert full.soc == pytest.approx(1.0) and half.soc == pytest.approx(0.5)
    assert half.voltage < full.voltage


def test_blocked_wheels_stall_or_slip(empty_world):
    w = empty_world
    stall = SimBackend(w, ("CYAN", 1), pose=_wall_test_pose(w), odom_noise_trans=0.0, odom_noise_rot=0.0)
    f = w.profile.field
    slip = SimBackend(w, ("CYAN", 2), pose=Pose2D(-3.0, f.y_max - 0.5, math.pi / 2), odom_slip=True,
                      odom_noise_trans=0.0, odom_noise_rot=0.0)
    for _ in range(40):
        stall.drive(0.5, 0.0, 0.0)
        slip.drive(0.5, 0.0, 0.0)
        w.step(0.1)
    assert stall.robot.collisions == 1 and slip.robot.collisions == 1
    truth = 0.5 - ROBOT.radius                  # both stopped at the wall
    assert stall.odometry().pose.x == pytest.approx(truth, abs=0.01)
    assert slip.odometry().pose.x > truth + 0.8  # wheels spun on for about 3 s
    assert slip.odometry().vx == pytest.approx(0.5)
