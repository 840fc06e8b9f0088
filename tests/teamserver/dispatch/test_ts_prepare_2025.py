"""2025: a machine left PREPARED 20 s without its workpiece breaks, so a feed's station is
prepared only once its robot says it waits there, docked (RobotStatus ``waiting_at``, set
by the trees' wait_station node): near the station is not enough (the robot may need
longer than 20 s to dock), and a RetrieveCap's robot first takes the carrier from the
shelf."""
from teamserver.knowledge import model as M
from teamserver.server import ServerConfig
from tests.support.teamserver import Lockstep
from tests.teamserver.production.test_ts_storage import T0, send_orders, setup_2025


def prepares(ls, machine):
    return [m for m in ls.refbox.received if m.DESCRIPTOR.name == "PrepareMachine"
            and m.machine == machine]


def _station(ls, name):
    return ls.server.production.world.positions()[name]


def _retrieve_cap(ls):
    setup_2025(ls)
    send_orders(ls, [{"id": 3, "delivery_period_begin": int(T0) + 400,
                      "delivery_period_end": int(T0) + 700}])
    ls.refbox.game_state("PRODUCTION", "RUNNING", T0 + 1)
    ls.step(n=4)
    [t] = [t for t in ls.server.kb.tasks.values()
           if t.kind == M.RETRIEVE_CAP and t.state == M.ASSIGNED]
    robot = next(a for a in ls.agents if a.number == t.robot)
    return t, robot


def test_a_feed_is_prepared_only_once_its_robot_waits_docked_at_the_station():
    ls = Lockstep("rcll2025", config=ServerConfig(prefill_caps=False))
    t, robot = _retrieve_cap(ls)
    assert ls.server.config.dispatch.stuck_timeout == 20.0          # from the profile
    x, y = _station(ls, t.machine)
    robot.pose = (x + 0.5, y, 0.0)                    # at the station, carrier in the gripper,
    robot.status(holding=True)                        # but not docked and waiting yet
    ls.step(n=4)
    assert not prepares(ls, t.machine)
    robot.status(holding=True, waiting_at="C-RS1")    # waiting at another station: no
    ls.step(n=4)
    assert not prepares(ls, t.machine)
    robot.status(holding=True, waiting_at=t.machine)
    ls.step(n=4)
    assert len(prepares(ls, t.machine)) == 1



def test_a_league_robot_that_stands_docked_at_its_feed_station_gets_it_prepared():
    """rll-bt teamserver --robots agenttask under 2025: a robot of the league sends no
    RobotStatus, so no ``waiting_at``; its beacons say the same (it runs the feed, stands
    at the station and has not moved for 2 s)."""
    ls = Lockstep("rcll2025", config=ServerConfig(prefill_caps=False, robots="agenttask"), league=True)
    t, robot = _retrieve_cap(ls)
    robot.running = next(v.agent_task for v in robot.tasks() if v.task_id == t.id)
    x, y = _station(ls, t.machine)

    def beacons(seconds, move=0.0):
        for _ in range(int(seconds)):
            robot.pose = (robot.pose[0] + move, robot.pose[1], robot.pose[2])
            robot.beat()
            ls.step(n=10)
    robot.pose = (x + 3.0, y, 0.0)
    beacons(4)                                        # standing, but far from the station
    assert not prepares(ls, t.machine)
    robot.pose = (x + 0.8, y, 0.0)
    beacons(4, move=-0.05)                            # at the station, still docking
    assert not prepares(ls, t.machine) and ls.server.kb.robots[robot.number].waiting_at is None
    beacons(4)                                        # standing still, docked
    assert ls.server.kb.robots[robot.number].waiting_at == t.machine
    assert len(prepares(ls, t.machine)) == 1
    robot.running = None
    beacons(2)
    assert ls.server.kb.robots[robot.number].waiting_at is None
