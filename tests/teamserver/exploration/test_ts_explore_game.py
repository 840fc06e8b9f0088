"""Exploration end to end in lockstep: scripted robots look at the zones they are
sent to; the server reports to the refbox before the deadline."""

from rll_bt import rules
from tests.support.teamserver import Lockstep

TRUTH_2016 = {"C-BS": 9, "C-DS": 4, "C-RS1": 2, "C-RS2": 19, "C-CS1": 23, "C-CS2": 6,
              "M-BS": 21, "M-DS": 16, "M-RS1": 14, "M-RS2": 7, "M-CS1": 11, "M-CS2": 18}
CODES = {"BS": 1, "DS": 2, "RS1": 4, "RS2": 5, "CS1": 3, "CS2": 6}
TRUTH_2025 = {"C-BS": 33, "C-DS": 17, "C-SS": 64, "C-RS1": 1045, "C-RS2": 26,
              "C-CS1": 54, "C-CS2": 13}


def twin_placement(profile, truth):
    full = dict(truth)
    for name, z in truth.items():
        full["M" + name[1:]] = profile.mirror_zone(z)
    return full


def play(ls, truth, lights, rotations, seconds, phase, dt=1.0):
    answered = {a.number: 0 for a in ls.agents}
    for step in range(int(seconds / dt)):
        ls.refbox.game_state(phase, "RUNNING", step * dt)
        for a in ls.agents:
            a.beat()
            tasks = a.tasks()
            for t in tasks[answered[a.number]:]:
                if t.WhichOneof("kind") != "explore_zone":
                    continue
                zone = t.explore_zone.zone
                for name, z in truth.items():
                    if z == zone:
                        a.observe(name, zone=z, zconf=0.9, lights=lights.get(name),
                                  lconf=0.92, orientation=rotations.get(name), oconf=0.92)
                a.t.send(a.ms.ZoneExplored(robot_id=a.number, zone=zone))
                a.result(t.task_id)
            answered[a.number] = len(tasks)
        ls.step(dt=dt)


def reported(ls):
    reports = [m for m in ls.refbox.received if m.DESCRIPTOR.name == "MachineReport"]
    return {e.name: e for e in reports[-1].machines} if reports else {}


def test_2016_every_machine_reported_with_zone_and_type_before_the_deadline():
    ls = Lockstep("rcll2016")
    p = rules.profile("rcll2016")
    for a in ls.agents:
        a.hello()
    ms = ls.refbox.ms
    info = ms.ExplorationInfo()
    for code, on in p.light_codes.items():
        sig = info.signals.add(type=f"TYPE{code:04d}")
        for light in on:
            sig.lights.add(color=ms.enum("LightColor").Value(light), state=1)
    for name, z in TRUTH_2016.items():
        if name.startswith("C-"):
            info.zones.add(zone=z, team_color=0)
    ls.refbox.game_state("EXPLORATION", "RUNNING", 0)
    ls.step()
    ls.refbox.public.send(info)
    lights = {n: CODES[n[2:]] for n in TRUTH_2016}
    play(ls, TRUTH_2016, lights, {}, 230, "EXPLORATION")
    got = reported(ls)
    assert set(got) == {n for n in TRUTH_2016 if n.startswith("C-")}
    for name, e in got.items():
        assert e.HasField("zone") and e.zone == TRUTH_2016[name]
        bits = CODES[name[2:]]
        assert e.type == f"TYPE{bits:04d}"
    branches = [t.params.get("branch") for t in ls.server.kb.tasks.values()]
    assert branches[0] == "opposite"


def test_2025_exploration_in_production_reports_zone_and_rotation():
    p = rules.profile("rcll2025")
    truth = twin_placement(p, TRUTH_2025)
    rot = {}
    for name, z in TRUTH_2025.items():
        r = 90 if name[2:4] in ("BS", "DS", "SS") else 45
        rot[name] = r
        twin_zone, twin_rot = p.mirror_placement("C-" + name[2:], z if z < 1000 else
                                                 p.mirror_zone(z), r)
        rot["M" + name[1:]] = twin_rot
    ls = Lockstep("rcll2025")
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("PRODUCTION", "RUNNING", 0)
    ls.step()
    # robots see what stands in the zones they visit, our half only
    half = {n: z for n, z in truth.items() if p.zone_team(z) == "CYAN"}
    play(ls, half, {}, rot, 170, "PRODUCTION")
    got = reported(ls)
    assert set(got) == {n for n in truth if n.startswith("C-")}
    for name, e in got.items():
        assert e.HasField("zone") and e.zone == truth[name], name
        assert e.HasField("rotation") and e.rotation == rot[name], name
    # swapped C-RS1 stands across: known through its twin and the rotation rules
    assert got["C-RS1"].zone == 1045
