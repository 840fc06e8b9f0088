"""Reliable delivery on a link: kept and repeated until acknowledged, by id, bounded."""
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm.reliable import AT_CANCEL, AT_FAILED, AT_SUCCEEDED, Reliable

TM = msgs.message_set("team")
LM = msgs.message_set("rcll2025")
AT = 502                                    # AgentTask's MSG_TYPE (COMP_ID 8000)


def task(tid):
    m = LM.AgentTask(team_color=0, task_id=tid, robot_id=1)
    m.move.waypoint = "C_Z33"
    return m


def cancel(tid):
    return LM.AgentTask(team_color=0, task_id=tid, robot_id=1, cancel_task=True)


def result(tid, status):
    m = task(tid)
    m.successful, m.canceled = status == "SUCCEEDED", status == "CANCELLED"
    return m


def test_kept_and_repeated_with_backoff_until_acknowledged():
    clock = SimClock()
    rel = Reliable(clock, retry=1.0, retry_max=4.0)
    assert rel.track(1, task(5))
    assert not rel.track(1, TM.Heartbeat(robot_id=1, seq=1))       # not delivered reliably
    times = []
    for _ in range(48):
        clock.advance(0.25)
        if rel.due(1):
            times.append(round(clock.now(), 1))
    assert times == [1.0, 3.0, 7.0, 11.0]                           # 1, 2, 4, then at most 4 s apart
    ack = TM.LinkAck(robot_id=1)
    ack.items.add(comp_id=8000, msg_type=AT, id=5 << 3)
    assert rel.on_ack(1, ack) == 1 and rel.pending(1) == []
    clock.advance(20.0)
    assert rel.due() == []


def test_the_receiver_acknowledges_every_copy_and_spots_repeats():
    rel = Reliable(SimClock())
    assert rel.received("srv", result(7, "SUCCEEDED"))
    assert not rel.received("srv", result(7, "SUCCEEDED"))          # the same result again
    assert rel.received("srv", result(7, "FAILED"))                 # another status is another message
    assert rel.received("srv", TM.Heartbeat(robot_id=1, seq=1))     # not delivered reliably: no ack, acted on
    assert rel.received("srv", cancel(7)) and rel.received("srv", task(7))     # a task, its cancel: two messages
    [(src, ack)] = rel.acks(lambda s: TM.LinkAck(robot_id=1))
    assert src == "srv" and [(i.comp_id, i.msg_type, i.id) for i in ack.items] == [
        (8000, AT, (7 << 3) | AT_SUCCEEDED), (8000, AT, (7 << 3) | AT_FAILED), (8000, AT, (7 << 3) | AT_CANCEL),
        (8000, AT, 7 << 3)]
    assert rel.acks(lambda s: TM.LinkAck(robot_id=1)) == []         # owed once
    sender = Reliable(SimClock())
    sender.track("srv", result(7, "SUCCEEDED"))
    sender.track("srv", result(7, "FAILED"))
    sender.track("srv", task(8))
    assert sender.on_ack("srv", ack) == 2 and [m.task_id for m in sender.pending("srv")] == [8]


def test_superseded_and_resent_at_once_when_the_link_is_back():
    clock = SimClock()
    rel = Reliable(clock, retry=2.0)
    rel.track(1, task(1))
    rel.track(1, task(2))
    rel.track(2, task(3))
    assert rel.forget(1, lambda m: m.task_id != 1) == 1
    clock.advance(1.0)
    assert [m.task_id for m in rel.resend_now(1)] == [2]
    clock.advance(1.5)
    assert [m.task_id for _, m in rel.due()] == [3]                 # task 2's wait started again
    clock.advance(0.6)
    assert [(d, m.task_id) for d, m in rel.due()] == [(1, 2)]


def test_bounded():
    rel = Reliable(SimClock(), max_pending=3, remember=2)
    for i in range(5):
        rel.track(1, task(i))
    assert [m.task_id for m in rel.pending(1)] == [2, 3, 4] and rel.counts["given_up"] == 2
    for i in range(4):
        rel.received(1, result(i, "SUCCEEDED"))
    assert rel.received(1, result(0, "SUCCEEDED"))                  # forgotten: acted on again (idempotent above)


def test_the_first_repeat_waits_for_twice_the_round_trip():
    clock = SimClock()
    rel = Reliable(clock, retry=1.0, retry_max=8.0)
    ack = TM.LinkAck(robot_id=1)
    ack.items.add(comp_id=8000, msg_type=AT, id=1 << 3)
    rel.track(1, task(1))
    clock.advance(0.5)                      # acknowledged before any repeat ...
    rel.on_ack(1, ack)
    assert rel.rtt[1] == 0.5 and rel.first_wait(1) == 1.0      # ... at least retry
    for i in range(2, 30):
        rel.track(1, task(i))
        clock.advance(3.0)
        assert rel.due() == [] or i < 4     # 3 s round trips: the waits grow to cover them
        ack.items[0].id = i << 3
        rel.on_ack(1, ack)
    assert 2.9 < rel.rtt[1] <= 3.0 and 5.8 < rel.first_wait(1) <= 6.0
