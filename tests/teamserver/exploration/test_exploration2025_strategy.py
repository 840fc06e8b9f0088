"""Algorithm 1 on the 2025 field (53 zones per half, a far tag sighting gives
zone and rotation): no visit for a machine already identified, a weak one
looked at again once every machine is placed instead of a random search, and
robots on blindly chosen zones redirected to an observed one."""
from rll_bt import rules
from teamserver.exploration.strategies import Algorithm1, RandomStrategy
from teamserver.exploration.view import ExplorationView
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import KnowledgeBase
from tests.support.teamserver import Lockstep

P25 = rules.profile("rcll2025")
Z = P25.zone_number
ZONES = P25.machine_zones("CYAN")
PLACES = {"C-BS": Z("C_Z33"), "C-DS": Z("C_Z17"), "C-SS": Z("C_Z64"), "M-RS1": Z("C_Z45"),
          "C-RS2": Z("C_Z26"), "C-CS1": Z("C_Z54"), "M-CS2": Z("C_Z13")}


def observe(kb, name, conf=0.95, oconf=None, robot="R1"):
    z = PLACES[name]
    kb.add_observation(M.Observation(name, M.ZONE, z, conf, robot))
    kb.add_observation(M.Observation(name, M.ORIENTATION, 45, conf if oconf is None else oconf, robot))


def view(kb, busy=()):
    return ExplorationView.from_kb(kb, "CYAN", ZONES, set(busy))


def test_an_observed_zone_whose_machine_is_identified_needs_no_visit():
    kb = KnowledgeBase(P25)
    observe(kb, "C-BS", conf=0.97)                   # identified from afar
    observe(kb, "C-CS1", conf=0.97, oconf=0.5)      # zone sure, rotation weak
    d = Algorithm1(seed=1).next_zone(view(kb))
    assert (d.zone, d.branch) == (PLACES["C-CS1"], "observed-unvisited")
    kb.mark_visited(PLACES["C-CS1"], 1.0)
    d = Algorithm1(seed=1).next_zone(view(kb))
    assert d.branch == "random-fallback" and d.zone not in (PLACES["C-BS"], PLACES["C-CS1"])


def test_every_machine_placed_a_weak_one_is_revisited_instead_of_a_random_search():
    kb = KnowledgeBase(P25)
    for name in PLACES:
        observe(kb, name, conf=0.97, oconf=0.6 if name in ("C-DS", "C-SS") else 0.97)
    for z in PLACES.values():
        kb.mark_visited(z, 1.0)
    v = view(kb)
    assert v.all_observed() and len(v.not_visited()) > 40
    d = Algorithm1(seed=1).next_zone(v)
    assert d.branch == "weak-revisit" and d.zone in (PLACES["C-DS"], PLACES["C-SS"])
    other = ({PLACES["C-DS"], PLACES["C-SS"]} - {d.zone}).pop()
    assert Algorithm1(seed=1).next_zone(view(kb, busy={d.zone})).zone == other
    # one machine not placed yet: search on
    kb2 = KnowledgeBase(P25)
    for name in list(PLACES)[:-1]:
        observe(kb2, name, conf=0.97, oconf=0.6 if name == "C-DS" else 0.97)
        kb2.mark_visited(PLACES[name], 1.0)
    assert Algorithm1(seed=1).next_zone(view(kb2)).branch == "random-fallback"


def test_only_a_blindly_chosen_zone_is_given_up_for_an_observed_one():
    kb = KnowledgeBase(P25)
    alg = Algorithm1(seed=1)
    assert alg.redirect(view(kb), "random-start") is None          # nothing observed yet
    observe(kb, "C-CS1", conf=0.7)
    for branch in ("opposite", "random-start", "random-fallback"):
        d = alg.redirect(view(kb), branch)
        assert (d.zone, d.branch) == (PLACES["C-CS1"], "observed-unvisited")
    assert alg.redirect(view(kb), "observed-unvisited") is None
    assert alg.redirect(view(kb, busy={PLACES["C-CS1"]}), "opposite") is None
    assert RandomStrategy(seed=1).redirect(view(kb), "random") is None


def test_in_game_a_robot_on_a_blind_zone_is_sent_to_a_zone_seen_meanwhile():
    ls = Lockstep("rcll2025")
    for a in ls.agents:
        a.hello()
    ls.refbox.game_state("PRODUCTION", "RUNNING", 0)
    ls.step(dt=1.0)
    first = {a.number: a.tasks()[-1] for a in ls.agents}
    assert {ls.server.kb.tasks[t.task_id].params["branch"] for t in first.values()} <= {
        "opposite", "random-start"}
    # robot 1, on its way, sees C-CS1 weakly: one robot is turned to it, the others go on
    ls.agents[0].observe("C-CS1", zone=PLACES["C-CS1"], zconf=0.6, orientation=45, oconf=0.6)
    ls.refbox.game_state("PRODUCTION", "RUNNING", 1.0)
    ls.step(dt=1.0)
    cancelled = [a for a in ls.agents if a.cancels()]
    assert len(cancelled) == 1
    robot = cancelled[0]
    new = robot.tasks()[-1]
    assert new.task_id != first[robot.number].task_id
    assert new.explore_zone.zone == PLACES["C-CS1"]
    assert ls.server.kb.tasks[new.task_id].params["branch"] == "observed-unvisited"
    assert ls.server.kb.tasks[first[robot.number].task_id].state == M.CANCELLED
