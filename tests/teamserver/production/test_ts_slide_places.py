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


def test_a_held_product_waiting_for_a_slide_base_nobody_started_on_gets_one_from_the_bs():
    """A product's workpiece waits for its second ring at C-RS1 (one base on the slide,
    none there); the base to pay for it is the product's own cap-less base, whose cap
    retrieval has not begun: a base is fetched from the BS instead (rcll2016 seed 2,
    rendered: two robots held products 372 s and 414 s at C-RS2 so).  Once the cap
    retrieval runs, its base counts as coming and none is fetched."""
    ls = Lockstep()
    production_setup(ls, [])
    ls.step(n=3)
    srv, kb, slides = ls.server, ls.server.kb, ls.server.production.slides
    ls.refbox.machines(ls.station_states, {"C-RS1": ("RING_BLUE", "RING_GREEN")}, **{"C-RS1": {"loaded_with": 0}})
    ls.step(n=3)
    p = srv.production.products.new("P", 1)

    def task(kind, params, **kw):
        t = M.Task(kb.next_id("task"), kind, params, product=p.id, **kw)
        kb.save_task(t)
        p.tasks = (*p.tasks, t.id)
        return t

    out = task(M.GET_WORKPIECE, {"machine": "C-RS1", "side": M.OUTPUT}, state=M.DONE)
    mount = task(M.MOUNT_RING, {"machine": "C-RS1", "ring_color": "RING_GREEN", "cost": 1,
                                "carry_from": out.id}, deps=(out.id,), carry=True, locks=("C-RS1",))
    retrieve = task(M.RETRIEVE_CAP, {"machine": "C-CS1"}, locks=("C-CS1", "C-CS1#cap"))
    capless = task(M.GET_WORKPIECE, {"machine": "C-CS1", "side": M.OUTPUT, "role": "capless"},
                   deps=(retrieve.id,))
    task(M.PUT_WORKPIECE, {"machine": "C-RS1", "side": M.SLIDE, "carry_from": capless.id},
         deps=(capless.id,), carry=True)
    kb.save_product(p)
    ls.clock.advance(10.0)                              # (past the slide's settle time)
    retrieve.state, retrieve.robot = M.ASSIGNED, 2
    kb.save_task(retrieve)
    assert slides.top_up_slides() == []                 # the cap-less base is on its way
    retrieve.state, retrieve.robot = M.PENDING, None
    kb.save_task(retrieve)
    [put] = slides.top_up_slides()                      # nobody has started on it
    get = kb.tasks[put.params["carry_from"]]
    assert get.machine == "C-BS" and put.machine == "C-RS1" and put.id in kb.tasks[mount.id].deps
    assert slides.top_up_slides() == []                 # (once)
