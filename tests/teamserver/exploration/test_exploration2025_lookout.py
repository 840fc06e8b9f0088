"""Going for a lacking rotation (2025): once every zone is reported the team
server keeps reporting and sends one robot to look at the tag faces of a
station whose rotation is not sure yet (teamserver.exploration.lookout)."""
import math

import pytest

from rll_bt import rules
from teamserver.exploration.lookout import LOOK, Lookout, face_viewpoints, is_look
from teamserver.exploration.symmetry import consistent_set
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from tests.support.teamserver import Lockstep

P25 = rules.profile("rcll2025")
Z = P25.zone_number
# the cyan-half stations of a layout (C-RS1 stands across, seen through its twin M-RS1)
TRUTH = {"C-BS": Z("C_Z33"), "C-DS": Z("C_Z17"), "C-SS": Z("C_Z64"), "M-RS1": Z("C_Z45"),
         "C-RS2": Z("C_Z26"), "C-CS1": Z("C_Z54"), "M-CS2": Z("C_Z13")}
ROT = {"C-BS": 90, "C-DS": 0, "C-SS": 90, "M-RS1": 45, "C-RS2": 45, "C-CS1": 45, "M-CS2": 45}


def centre_pose(name):
    x, y = P25.zone_centre(TRUTH[name])
    return (x, y, math.radians(ROT[name]))


def known_kb(weak=("C-DS",), weak_conf=0.6):
    """Every zone known and reported; the rotations of ``weak`` only at ``weak_conf``."""
    kb = KnowledgeBase(P25)
    for name, z in TRUTH.items():
        conf = weak_conf if name in weak else 0.95
        kb.add_observation(M.Observation(name, M.ZONE, z, 0.95, "R1", 0.0))
        kb.add_observation(M.Observation(name, M.ORIENTATION, ROT[name], conf, "R1", 0.0))
        kb.add_observation(M.Observation(name, M.POSE, centre_pose(name), 0.95, "R1", 0.0))
    cs = consistent_set(P25, kb.machines)
    for name, g in cs.own("CYAN").items():
        kb.mark_reported(name, {M.ZONE: g.zone} if name in weak else
                         {M.ZONE: g.zone, "rotation": g.orientation})
    return kb, cs


def test_face_viewpoints_stand_in_front_of_the_input_and_output_faces():
    vps = face_viewpoints(P25, (3.5, 4.5, 0.0), distance=0.9)
    d = P25.mps.depth / 2 + 0.9
    assert vps[0][:2] == pytest.approx((3.5 + d, 4.5)) and vps[0][2] == pytest.approx(math.pi)
    assert vps[1][:2] == pytest.approx((3.5 - d, 4.5)) and vps[1][2] == pytest.approx(0.0)
    # next to the wall x = 7 only the output face can be looked at; a station in front hides one
    assert len(face_viewpoints(P25, (6.5, 2.5, 0.0))) == 1
    assert len(face_viewpoints(P25, (3.5, 4.5, 0.0), others=[(3.5 + d, 4.5)])) == 1


def test_the_least_sure_unreported_rotation_is_the_target_with_face_viewpoints():
    kb, cs = known_kb(weak=("C-DS", "C-SS"), weak_conf=0.6)
    # the same visit, a little surer: still one vote, at 0.7
    kb.add_observation(M.Observation("C-SS", M.ORIENTATION, 90, 0.7, "R1", 5.0))
    look = Lookout(P25, "C")
    cs = consistent_set(P25, kb.machines)
    assert look.lacking(cs, kb.reported) == ["C-DS", "C-SS"]
    (target,) = look.targets(kb, cs, time_left=100.0)
    assert target.machine == "C-DS" and target.zone == TRUTH["C-DS"]
    assert len(target.viewpoints) == 2
    x, y, _ = centre_pose("C-DS")
    for vx, vy, th in target.viewpoints:
        assert math.hypot(vx - x, vy - y) == pytest.approx(P25.mps.depth / 2 + 0.9)
        assert math.cos(th - math.atan2(y - vy, x - vx)) == pytest.approx(1.0)   # facing it


def test_no_look_when_time_is_short_when_sure_or_in_2016():
    kb, cs = known_kb()
    look = Lookout(P25, "C")
    assert look.targets(kb, cs, time_left=10.0) == []          # the last-seconds report takes over
    kb2, cs2 = known_kb(weak=())
    assert look.lacking(cs2, kb2.reported) == []
    assert not Lookout(rules.profile("rcll2016"), "C").active()


def test_one_look_at_a_time_at_most_three_per_machine_and_a_sure_rotation_ends_it():
    kb, cs = known_kb()
    look = Lookout(P25, "C")
    t = M.Task(1, M.EXPLORE_ZONE, {"zone": TRUTH["C-DS"], LOOK: "C-DS"}, state=M.ASSIGNED, robot=2)
    kb.save_task(t)
    assert is_look(t)
    assert look.targets(kb, cs, 100.0) == []                   # one robot looks already
    assert look.done_looks(kb, cs) == []
    kb.add_observation(M.Observation("C-DS", M.ORIENTATION, 0, 0.97, "R2", 30.0))
    cs = consistent_set(P25, kb.machines)
    assert look.done_looks(kb, cs) == [t]                      # sure now: the look can stop
    kb2, cs2 = known_kb()
    for i in range(3):
        kb2.save_task(M.Task(10 + i, M.EXPLORE_ZONE, {"zone": 1, LOOK: "C-DS"}, state=M.FAILED))
    assert look.targets(kb2, cs2, 100.0) == []


def test_the_robot_sent_is_one_that_has_not_reported_the_station_yet():
    kb, cs = known_kb()
    (target,) = Lookout(P25, "C").targets(kb, cs, 100.0)
    x, y, _ = centre_pose("C-DS")
    near_voter = M.Robot(1, pose=(x + 1.0, y, 0.0))            # R1 saw C-DS at 0.6 already
    far_other = M.Robot(2, pose=(x + 4.0, y, 0.0))
    assert Lookout.pick_robot([near_voter, far_other], target, kb) is far_other
    assert Lookout.pick_robot([near_voter], target, kb) is near_voter
    assert Lookout.pick_robot([], target, kb) is None


def test_in_game_the_server_sends_a_look_after_the_zones_and_reports_the_rotation():
    ls = Lockstep("rcll2025")
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("PRODUCTION", "RUNNING", 0)
    ls.step()
    looks = []
    answered = {a.number: 0 for a in ls.agents}
    for step in range(120):
        ls.refbox.game_state("PRODUCTION", "RUNNING", float(step))
        for a in ls.agents:
            a.beat()
            tasks = a.tasks()
            for t in tasks[answered[a.number]:]:
                if t.WhichOneof("kind") != "explore_zone":
                    continue
                zone = t.explore_zone.zone
                for name, z in TRUTH.items():
                    if z != zone:
                        continue
                    if t.explore_zone.viewpoints:        # a look at the faces: a sure rotation
                        looks.append((step, name, list(t.explore_zone.viewpoints)))
                        oconf = 0.97
                    else:                                # the DS's tag only seen obliquely
                        oconf = 0.3 if name == "C-DS" else 0.95
                    a.observe(name, zone=z, zconf=0.95, orientation=ROT[name], oconf=oconf,
                              pose=centre_pose(name), pconf=0.95)
                a.t.send(a.ms.ZoneExplored(robot_id=a.number, zone=zone))
                a.result(t.task_id)
            answered[a.number] = len(tasks)
        ls.step(dt=1.0)
        if looks and "rotation" in ls.server.kb.reported.get("C-DS", {}):
            break
    reported = ls.server.kb.reported
    assert all(M.ZONE in reported.get(n, {}) for n in P25.machines("CYAN"))
    assert looks and looks[0][1] == "C-DS" and len(looks[0][2]) == 2
    assert reported["C-DS"]["rotation"] == 0
    entries = [m for m in ls.refbox.received if m.DESCRIPTOR.name == "MachineReport"]
    assert {e.name: e.rotation for e in entries[-1].machines}["C-DS"] == 0
    # the look is not cancelled as "exploration is over": only exploring robots were
    look_tasks = [t for t in ls.server.kb.tasks.values() if is_look(t)]
    assert look_tasks and all(t.state == M.DONE for t in look_tasks)
