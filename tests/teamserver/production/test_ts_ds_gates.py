"""A DS left PREPARED with a gate no product will use (2016: no timeout of a PREPARED station,
no ResetMachine): it is fed a spare base when a finished product needs another gate, and kept
when a product is made again or finished for that gate."""
from teamserver.knowledge import model as M
from tests.support.teamserver import Lockstep, abandon_all_products, production_setup


def ds_prepared_for_gate_1(state):
    """Orders 1 (gate 1) and 2 (gate 2), their products given up, and C-DS left PREPARED
    by a delivery for gate 1 that ended ``state``: (lockstep, knowledge base, feed monitor)."""
    ls = Lockstep()
    production_setup(ls, [{"id": 1, "delivery_gate": 1}, {"id": 2, "delivery_gate": 2}])
    srv = ls.server
    kb, feeds = srv.kb, srv.dispatcher.feeds
    ls.step(n=3)
    abandon_all_products(srv)
    old = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 1},
                 state=state, prepare={"machine": "C-DS", "ds": {"gate": 1}})
    kb.save_task(old)
    feeds.sent(old)
    ls.station_states["C-DS"] = "PREPARED"
    ls.refbox.machines(ls.station_states)
    ls.step()
    return ls, kb, feeds


def test_a_station_waiting_with_another_gate_is_fed_a_spare_base_first():
    # the DS waits with gate 1 of a delivery that is over; order 2 needs gate 2
    ls, kb, feeds = ds_prepared_for_gate_1(M.DONE)
    want2 = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 2},
                   prepare={"machine": "C-DS", "ds": {"gate": 2}}, carry=True, holder=1)
    want1 = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 1},
                   prepare={"machine": "C-DS", "ds": {"gate": 1}}, carry=True, holder=2)
    assert not feeds.accepts(want2)          # it would be delivered at gate 1
    assert feeds.accepts(want1) and feeds.adoptable(want1)
    kb.save_task(want2)
    [flush] = feeds.unstick()
    assert feeds.unstick() == []             # one at a time
    steps = kb.tasks_of(flush.tasks)
    assert [t.kind for t in steps] == [M.GET_WORKPIECE, M.DELIVER]
    assert steps[0].machine == "C-BS" and steps[0].prepare["bs"]["side"] == M.OUTPUT
    assert steps[1].prepare is None and steps[1].carry and steps[1].deps == (steps[0].id,)
    assert steps[1].params["gate"] == 1 and steps[1].locks == ("C-DS",)
    # once the spare base went through, the DS is IDLE and takes gate 2
    ls.station_states["C-DS"] = "PROCESSING"
    ls.refbox.machines(ls.station_states)
    ls.station_states["C-DS"] = "IDLE"
    ls.refbox.machines(ls.station_states)
    ls.step()
    assert feeds.instruction("C-DS") is None and feeds.accepts(want2)


def test_a_ds_waiting_for_a_product_made_again_is_flushed_for_a_finished_one():
    """2016 has no timeout of a PREPARED station and no ResetMachine: a delivery the DS
    never took leaves it PREPARED with that gate.  While the lost product is made again
    (its delivery wants that gate, but its workpiece is far from done), a finished
    product for another gate must not wait for it: the DS gets a spare base first."""
    ls, kb, feeds = ds_prepared_for_gate_1(M.FAILED)
    # order 1's product made again: its delivery waits for a cap mount not yet done
    cap = M.Task(kb.next_id("task"), M.MOUNT_CAP, {"machine": "C-CS1"},
                 prepare={"machine": "C-CS1", "cs": {"operation": "MOUNT_CAP"}})
    again = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 1},
                   prepare={"machine": "C-DS", "ds": {"gate": 1}}, deps=(cap.id,), carry=True)
    for t in (cap, again):
        kb.save_task(t)
    assert feeds.unstick() == []             # nothing else to deliver: keep the gate
    done = M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": 2},
                  prepare={"machine": "C-DS", "ds": {"gate": 2}}, carry=True, holder=1)
    kb.save_task(done)
    assert not feeds.accepts(done)
    [flush] = feeds.unstick()
    steps = kb.tasks_of(flush.tasks)
    assert [t.kind for t in steps] == [M.GET_WORKPIECE, M.DELIVER]
    assert steps[1].params["gate"] == 1 and steps[1].prepare is None


def test_a_ds_waiting_with_the_gate_of_a_finished_product_is_not_flushed():
    """The same, but order 1's product is finished too: it uses the waiting gate."""
    ls, kb, feeds = ds_prepared_for_gate_1(M.FAILED)
    for gate, holder in ((1, 2), (2, 1)):
        kb.save_task(M.Task(kb.next_id("task"), M.DELIVER, {"machine": "C-DS", "gate": gate},
                            prepare={"machine": "C-DS", "ds": {"gate": gate}}, carry=True,
                            holder=holder))
    assert feeds.unstick() == []
