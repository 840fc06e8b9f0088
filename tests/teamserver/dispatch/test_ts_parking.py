"""Parking: idle robots in front of a station are sent to a free spot, never
at the cost of real work; failed discards are not resent at once."""
import math

import numpy as np

from teamserver.dispatch import parking
from teamserver.knowledge import model as M
from tests.support.teamserver import RS_2016, Lockstep, production_setup, task_kinds


def far_spots(n):
    """``n`` spots well away from every station as the harness reports them, and each other."""
    ls = Lockstep()
    production_setup(ls, [])
    approach, centres = parking.station_points(ls.server.kb, ls.server.profile)
    profile = ls.server.profile
    ls.close()
    out = []
    for x, y in parking.candidates(profile):
        if parking.clearance(np.array([[x, y]]), profile, approach, centres, out)[0] >= 1.3:
            out.append((float(x), float(y)))
            if len(out) == n:
                return out
    raise AssertionError("no free spots")


def wait(ls, seconds):
    """Step ``seconds`` of server time, the robots reporting every second."""
    for _ in range(int(round(seconds))):
        for a in ls.agents:
            a.status()
        ls.step(n=10)


def setup():
    """Robot 1 in front of the BS (zone 9, centre (5, 0.75)), robots 2 and 3 far from everything."""
    f1, f2 = far_spots(2)
    ls = Lockstep()
    for a, pose in zip(ls.agents, [(4.2, 0.75, 0.0), (*f1, 0.0), (*f2, 0.0)]):
        a.pose = pose
    production_setup(ls, [])
    ls.step(n=3)
    return ls, f1, f2


def test_an_idle_robot_at_a_station_is_parked_and_one_far_away_is_not():
    ls, f1, f2 = setup()
    parks = ls.agents[0].parks()
    assert len(parks) == 1 and not ls.agents[1].parks() and not ls.agents[2].parks()
    target = parks[0].go_to.target
    approach, _ = parking.station_points(ls.server.kb, ls.server.profile)
    assert not parking.in_the_way((target.x, target.y), approach)
    assert math.hypot(target.x - f1[0], target.y - f1[1]) > 0.5          # not onto another robot
    assert math.hypot(target.x - f2[0], target.y - f2[1]) > 0.5
    # it arrives: parked, it is left alone
    ls.agents[0].pose = (target.x, target.y, target.theta)
    ls.agents[0].status()
    ls.agents[0].result(parks[0].task_id)
    ls.step(n=5)
    assert len(ls.agents[0].parks()) == 1
    assert ls.server.kb.tasks[parks[0].task_id].state == M.DONE
    ls.close()


def test_a_failed_park_is_not_resent_at_once():
    ls, f1, f2 = setup()
    (p,) = ls.agents[0].parks()
    ls.agents[0].result(p.task_id, status="FAILED", error="NAVIGATION_FAILED")
    ls.step(n=20)
    assert len(ls.agents[0].parks()) == 1
    ls.close()


def test_a_parking_robot_gets_ready_work_and_its_park_is_cancelled():
    ls, f1, f2 = setup()
    (p,) = ls.agents[0].parks()
    production_setup(ls, [{"id": 1}])                          # work appears while it drives
    ls.step(n=3)
    assert ("get_workpiece", "C-BS") in [k[1:] for k in task_kinds(ls.agents[0])]
    assert p.task_id in [c.task_id for c in ls.agents[0].cancels()]
    assert ls.server.kb.tasks[p.task_id].state == M.CANCELLED
    ls.close()


def _full_slides(ls):
    """Both ring stations' slides hold 3 bases: no room for a discard there."""
    ls.refbox.machines(ls.station_states, RS_2016,
                       **{rs: {"loaded_with": 3} for rs in ("C-RS1", "C-RS2")})
    ls.step(n=2)


def test_a_failed_discard_waits_before_the_next_one():
    f1, f2, f3 = far_spots(3)
    ls = Lockstep()
    for a, f in zip(ls.agents, (f1, f2, f3)):
        a.pose = (*f, 0.0)
    production_setup(ls, [])
    _full_slides(ls)                       # dropped where the robot stands
    kb, disp = ls.server.kb, ls.server.dispatcher
    r = kb.robots[1]
    r.holding = "?"
    kb.save_robot(r)
    ls.step(n=2)
    discards = lambda: [t for t in ls.agents[0].tasks() if t.WhichOneof("kind") == "discard"]  # noqa: E731
    assert len(discards()) == 1
    ls.agents[0].result(discards()[0].task_id, status="FAILED", error="TIMEOUT", holding=True)
    wait(ls, 3)                                                    # still waiting
    assert len(discards()) == 1
    wait(ls, 3)                                                    # after the 5 s back-off: again
    assert len(discards()) == 2
    ls.agents[0].result(discards()[1].task_id, status="FAILED", error="PUT_FAILED", holding=True)
    wait(ls, 7)                                                    # the wait doubles
    assert len(discards()) == 2
    wait(ls, 4)
    assert len(discards()) == 3
    assert disp.config.discard_backoff == 5.0
    ls.close()


def test_a_workpiece_nothing_needs_goes_on_the_nearest_slide_with_room():
    """A base on a ring station's slide counts as an additional base (+2); dropped on
    the floor it is a referee's call (2025: -10).  A full slide (3) takes no more."""
    f1, f2, f3 = far_spots(3)
    ls = Lockstep()
    for a, f in zip(ls.agents, (f1, f2, f3)):
        a.pose = (*f, 0.0)
    production_setup(ls, [])
    kb = ls.server.kb
    pos = ls.server.production.world.positions()
    near, other = sorted(("C-RS1", "C-RS2"), key=lambda m: math.dist(pos[m], f1))
    ls.refbox.machines(ls.station_states, RS_2016, **{near: {"loaded_with": 3},
                                                      other: {"loaded_with": 2}})
    ls.step(n=2)
    r = kb.robots[1]
    r.holding = "?"
    kb.save_robot(r)
    ls.step(n=2)
    [d] = [t for t in ls.agents[0].tasks() if t.WhichOneof("kind") == "discard"]
    assert d.discard.machine == other and d.discard.side == "SLIDE"
    ls.close()
