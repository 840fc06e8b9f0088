"""How the PyBullet world counts collisions (the number game reports and
the skills' tests compare): one event per contact, however often the
robot pushes against the same thing before it has left it."""
import pytest

from rll_bt.backend import Pose2D

sim = pytest.importorskip("backends.sim")


def push(world, robot, vx, seconds):
    t_end = world.time + seconds
    while world.time < t_end - 1e-9:
        robot.drive(vx, 0.0, 0.0, world.time)
        world.step(0.05)
    robot.stop(world.time)
    world.step(1.0)


def test_pushing_again_against_the_same_wall_is_one_contact_leaving_it_makes_the_next_a_new_one():
    world = sim.World("rcll2016", seed=1)
    f = world.profile.field
    robot = world.add_robot("CYAN", 1, pose=Pose2D(f.x_max - 0.5, 3.0, 0.0))   # 0.275 m from the wall, facing it
    push(world, robot, 0.3, 2.0)
    assert world.collision_count == 1
    log = world.collision_log[0]
    assert log.obstacle == "wall" and log.robot == ("CYAN", 1)
    assert log.pose.x == pytest.approx(f.x_max - robot.radius, abs=0.01) and log.speed > 0.1
    for _ in range(3):                                # pause, push again: still the same contact
        push(world, robot, 0.1, 0.5)
    assert world.collision_count == 1
    assert robot.blocked_steps > 10
    push(world, robot, -0.2, 0.5)                     # leave the wall ...
    assert world.clearance("CYAN", 1) > 0.05
    push(world, robot, 0.3, 2.0)                      # ... and hit it again
    assert world.collision_count == 2
