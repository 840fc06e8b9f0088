"""No wrong light code reaches the refbox: the team server reports a station's
light code only on two sure views that agree and that no sure view
contradicts, whatever the time left; one sure view alone, and confident
views, of one robot or of two, do not report it.  The robot side is the real pipeline (the
exploration's sighting collector, the machine map, the agent's observation
feed) reading a detector whose answers the test scripts."""
from types import SimpleNamespace

from rll_bt import rules
from rll_bt.agent.observations import ObservationFeed
from rll_bt.backend import Detections, LightDetection, Pose2D
from skills.exploration.sightings import SightingCollector
from skills.machines import MachineMap
from teamserver.exploration.lights import LightGate
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from tests.support.teamserver import Lockstep

P16 = rules.profile("rcll2016")
ZONES = {"C-CS1": 11, "M-CS1": P16.mirror_zone(11)}
GREEN_YELLOW = 3          # C-CS1's code in this game (its type string TYPE0003)
RED_GREEN = 5             # what the fooled detector reads


def probs(state, p):
    return tuple(p if s == state else (1.0 - p) / 7 for s in range(8))


class ScriptedReader:
    """The robot's detections: the tag of a station in view and its tower read
    as ``answer(position)`` says, (state, probability)."""

    def __init__(self, answer):
        self.answer, self.next = answer, None

    def detections(self):
        return self.next


class Robot:
    """One robot's perception and observation feed, its messages sent to the team server."""

    def __init__(self, ls, agent, answer):
        self.ls, self.agent = ls, agent
        self.reader = ScriptedReader(answer)
        self.where = Pose2D(0.0, 0.0, 0.0)
        self.map = MachineMap()
        self.feed = ObservationFeed(P16, ls.clock, robot_id=agent.number)
        self.feed.attach(self.map)
        ctx = SimpleNamespace(profile=P16, tags=self.reader, pose=lambda: self.where, estimate=lambda: None,
                              machines=self.map)
        self.collector = SightingCollector(ctx)

    def look(self, machine, seconds, at, dt=0.2):
        """Stand at ``at`` reading ``machine``'s tower for ``seconds``."""
        self.where = Pose2D(at[0], at[1], 0.0)
        tag = P16.tag_ids(machine)[0]
        for _ in range(int(seconds / dt)):
            state, p = self.reader.answer(machine, at)
            self.reader.next = Detections(self.ls.clock.now(), (), (
                LightDetection((0, 0, 8, 33), state, p, probs(state, p), "front", tag_id=tag),), None)
            self.collector.look()
            for m in self.feed.drain():
                self.agent.t.send(m)
            self.agent.observe(machine, zone=ZONES[machine], zconf=0.95)
            self.agent.beat()
            self.ls.refbox.game_state("EXPLORATION", "RUNNING", self.ls.clock.now())
            self.ls.step(dt=dt)
            check_no_wrong_type(self.ls)


def start(ls):
    ms = ls.refbox.ms
    for a in ls.agents:
        a.hello()
    info = ms.ExplorationInfo()
    for code, on in P16.light_codes.items():
        sig = info.signals.add(type=f"TYPE{code:04d}")
        for light in on:
            sig.lights.add(color=ms.enum("LightColor").Value(light), state=1)
    info.zones.add(zone=ZONES["C-CS1"], team_color=0)
    ls.refbox.game_state("EXPLORATION", "RUNNING", 0)
    ls.step()
    ls.refbox.public.send(info)
    ls.step()


def reported_types(ls):
    out = []
    for m in ls.refbox.received:
        if m.DESCRIPTOR.name == "MachineReport":
            out += [(e.name, e.type) for e in m.machines if e.type]
    return out


def check_no_wrong_type(ls):
    for name, t in reported_types(ls):
        assert (name, t) == ("C-CS1", f"TYPE{GREEN_YELLOW:04d}"), f"wrong report {name} {t}"


def test_a_wrong_unsure_view_then_right_views_report_only_the_right_code_once_a_view_is_sure():
    ls = Lockstep("rcll2016", robots=2)
    start(ls)

    def answer(machine, at):      # fooled (and unsure) from where it stands first, right elsewhere
        return (RED_GREEN, 0.8) if at == (0.0, 0.0) else (GREEN_YELLOW, 0.95)

    r = Robot(ls, ls.agents[0], answer)
    r.look("C-CS1", 3.0, (0.0, 0.0))
    assert r.collector.light_unsure("C-CS1")
    assert reported_types(ls) == []
    r.look("C-CS1", 3.0, (0.0, 0.45))          # a second view, sideways: right, confident
    r.look("C-CS1", 3.0, (0.0, -0.45))         # a third agrees
    Robot(ls, ls.agents[1], answer).look("C-CS1", 3.0, (1.0, 1.0))     # and another robot's
    assert reported_types(ls) == []            # confident is not sure
    r.reader.answer = lambda machine, at: (GREEN_YELLOW, 0.995)
    r.look("C-CS1", 3.0, (0.5, 0.0))           # a sure view
    assert reported_types(ls) == []            # alone
    r.look("C-CS1", 3.0, (1.0, 0.0))           # and a second one from another place
    assert set(reported_types(ls)) == {("C-CS1", f"TYPE{GREEN_YELLOW:04d}")}


def test_confident_wrong_views_of_two_robots_are_not_reported_the_twins_sure_views_are():
    # the rendered game of seed 2: two robots read CS2's green lamp unlit at 0.94-0.97
    ls = Lockstep("rcll2016", robots=2)
    start(ls)
    wrong = lambda machine, at: (RED_GREEN ^ 1, 0.94 + 0.01 * at[0])      # noqa: E731
    Robot(ls, ls.agents[0], wrong).look("C-CS1", 3.0, (0.0, 0.0))
    Robot(ls, ls.agents[1], wrong).look("C-CS1", 3.0, (3.0, 0.0))
    light = ls.server.kb.estimate("C-CS1", M.LIGHT)
    assert light.value == ("RED",) and light.confidence >= 0.9            # the fused belief would report it
    ls.refbox.game_state("EXPLORATION", "RUNNING", P16.phases.exploration_deadline - 5.0)
    ls.step(n=20)                                                         # the last seconds: report what pays
    assert reported_types(ls) == []
    twin = Robot(ls, ls.agents[1], lambda machine, at: (GREEN_YELLOW, 0.998))
    twin.look("M-CS1", 3.0, (4.0, 4.0))
    twin.look("M-CS1", 3.0, (4.5, 4.0))
    assert set(reported_types(ls)) == {("C-CS1", f"TYPE{GREEN_YELLOW:04d}")}


def test_two_sure_views_are_reported_over_many_confident_wrong_ones_of_the_fused_belief():
    # the rendered game of seed 1: one robot read RS2's green lamp unlit from four places, then sure
    ls = Lockstep("rcll2016", robots=1)
    start(ls)
    r = Robot(ls, ls.agents[0], lambda machine, at: (RED_GREEN ^ 1, 0.947 + 0.01 * at[0]))
    for x in (0.0, 1.0, 2.0, 3.0):
        r.look("C-CS1", 2.0, (x, 0.0))
    assert reported_types(ls) == []
    r.reader.answer = lambda machine, at: (GREEN_YELLOW, 0.993)
    r.look("C-CS1", 2.0, (4.0, 0.0))
    r.look("C-CS1", 2.0, (4.5, 0.0))
    assert ls.server.kb.estimate("C-CS1", M.LIGHT).value == ("RED",)   # what all views together say
    assert set(reported_types(ls)) == {("C-CS1", f"TYPE{GREEN_YELLOW:04d}")}


def test_gate_rules():
    kb = KnowledgeBase(P16)
    gate = LightGate(kb)
    gy, rg = ("GREEN", "YELLOW"), ("GREEN", "RED")

    def view(robot, view, code, conf, machine="C-CS1"):
        kb.add_observation(M.Observation(machine, M.LIGHT, code, conf, M.view_source(robot, view)))

    assert gate.passes("C-CS1", gy)                           # nothing read through views: not gated
    view("R1", 1, gy, 0.95)
    view("R2", 1, gy, 0.97)
    assert not gate.passes("C-CS1", gy)                       # confident views, of two robots: not enough
    view("R1", 1, gy, 0.995)
    assert not gate.passes("C-CS1", gy) and gate.code("C-CS1") is None   # one sure view: not alone
    assert LightGate(kb, min_sure=1).passes("C-CS1", gy)      # (unless one is all that is asked for)
    view("R2", 1, gy, 0.991)
    assert gate.passes("C-CS1", gy) and gate.code("C-CS1") == gy          # two sure views agree
    view("R2", 2, rg, 0.993)
    assert not gate.passes("C-CS1", gy) and not gate.passes("C-CS1", rg)   # contradicted by a sure view
    view("R3", 1, gy, 0.992, machine="M-CS1")
    assert gate.passes("C-CS1", gy) and gate.code("C-CS1") == gy          # three (one of the twin) against one
    view("R1", 2, rg, 0.98)
    assert gate.passes("C-CS1", gy)                           # a confident view does not hold it back
    assert len(gate.views("C-CS1")) == 5                      # one vote a view: its latest reading


def test_a_single_wrong_sure_view_never_becomes_a_report():
    # the rendered game of seed 1 at 112b3d3: one view read M-DS's green and yellow as yellow at 0.993
    kb = KnowledgeBase(P16)
    gate = LightGate(kb)
    kb.add_observation(M.Observation("M-DS", M.LIGHT, ("YELLOW",), 0.993, M.view_source("R2", 1)))
    assert gate.code("C-DS") is None and gate.code("M-DS") is None
    kb.add_observation(M.Observation("M-DS", M.LIGHT, ("GREEN", "YELLOW"), 0.998, M.view_source("R3", 1)))
    assert gate.code("M-DS") is None                          # one against one
    for n in (2, 3):
        kb.add_observation(M.Observation("C-DS", M.LIGHT, ("GREEN", "YELLOW"), 0.997, M.view_source("R1", n)))
    assert gate.code("M-DS") == gate.code("C-DS") == ("GREEN", "YELLOW")   # three against one
