"""Places on a ring station's slide: a base a robot holds or fetches for it keeps its
place there."""
from teamserver.knowledge import model as M
from tests.support.teamserver import Lockstep, abandon_all_products, production_setup


def test_a_base_a_robot_holds_or_fetches_for_a_slide_keeps_its_place_there():
    """C-RS1's slide holds 2 of 3: a robot fetching a base for it keeps the last place,
    so a cap-less base to discard goes elsewhere (rcll2025 seed 10 with 20 % loss: a
    discard took it, and the robot held its base 380 s); of two robots holding bases
    for it, the older put goes."""
    ls = Lockstep()
    production_setup(ls, [{"id": 5, "complexity": 1, "rings": ["RING_BLUE"]}])
    srv, kb, slides = ls.server, ls.server.kb, ls.server.production.slides
    ls.step(n=3)
    abandon_all_products(srv)
    ls.refbox.machines(ls.station_states, {"C-RS1": ("RING_BLUE", "RING_GREEN")}, **{"C-RS1": {"loaded_with": 2}})
    ls.step(n=3)
    assert slides.room("C-RS1") == 1
    gets = [M.Task(kb.next_id("task"), M.GET_WORKPIECE, {"machine": "C-BS", "side": M.OUTPUT},
                   state=M.ASSIGNED, robot=n) for n in (1, 2)]
    puts = [M.Task(kb.next_id("task"), M.PUT_WORKPIECE, {"machine": "C-RS1", "side": M.SLIDE,
                                                          "carry_from": g.id}, deps=(g.id,), carry=True)
            for g in gets]
    for t in gets[:1] + puts[:1]:
        kb.save_task(t)
    assert slides.room("C-RS1") == 0                   # robot 1 is fetching a base for it
    assert slides.room("C-RS1", puts[0].id) == 1 and slides.slide_ready(puts[0])
    for t in gets[1:] + puts[1:]:
        kb.save_task(t)
    for g in gets:                                      # both hold their bases now
        g.state = M.DONE
        kb.save_task(g)
    assert slides.slide_ready(puts[0]) and not slides.slide_ready(puts[1])
