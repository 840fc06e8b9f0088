"""Reliable delivery on a link: kept and repeated until acknowledged, by id, bounded."""
from rll_bt import msgs
from rll_bt.clock import SimClock
from rll_bt.comm.reliable import Reliable

TM = msgs.message_set("team")


def task(tid):
    m = TM.Task(task_id=tid, robot_id=1)
    m.go_to.zone = 3
    return m


def result(tid, status):
    return TM.TaskResult(task_id=tid, robot_id=1, status=TM.TaskResult.Status.Value(status))


def test_kept_and_repeated_with_backoff_until_acknowledged():
    clock = SimClock()
    rel = Reliable(clock, retry=1.0, retry_max=4.0)
    assert rel.track(1, task(5))
    assert not rel.track(1, TM.Heartbeat(robot_id=1, seq=1))       # not delivered reliably
    assert not rel.track(1, result(5, "RUNNING"))                   # a progress report: neither
    times = []
    for _ in range(48):
        clock.advance(0.25)
        if rel.due(1):
            times.append(round(clock.now(), 1))
    assert times == [1.0, 3.0, 7.0, 11.0]                           # 1, 2, 4, then at most 4 s apart
    ack = TM.LinkAck(robot_id=1)
    ack.items.add(comp_id=3000, msg_type=10, id=5)
    assert rel.on_ack(1, ack) == 1 and rel.pending(1) == []
    clock.advance(20.0)
    assert rel.due() == []


def test_the_receiver_acknowledges_every_copy_and_spots_repeats():
    rel = Reliable(SimClock())
    assert rel.received("srv", result(7, "SUCCEEDED"))
    assert not rel.received("srv", result(7, "SUCCEEDED"))          # the same result again
    assert rel.received("srv", result(7, "FAILED"))                 # another status is another message
    assert rel.received("srv", result(7, "RUNNING"))                # progress: no ack, always acted on
    [(src, ack)] = rel.acks(lambda s: TM.LinkAck(robot_id=1))
    assert src == "srv" and [(i.msg_type, i.id) for i in ack.items] == [(11, (7 << 3) | 2), (11, (7 << 3) | 3)]
    assert rel.acks(lambda s: TM.LinkAck(robot_id=1)) == []         # owed once
    sender = Reliable(SimClock())
    sender.track("srv", result(7, "SUCCEEDED"))
    sender.track("srv", result(7, "FAILED"))
    assert sender.on_ack("srv", ack) == 2


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
    ack.items.add(comp_id=3000, msg_type=10, id=1)
    rel.track(1, task(1))
    clock.advance(0.5)                      # acknowledged before any repeat ...
    rel.on_ack(1, ack)
    assert rel.rtt[1] == 0.5 and rel.first_wait(1) == 1.0      # ... at least retry
    for i in range(2, 30):
        rel.track(1, task(i))
        clock.advance(3.0)
        assert rel.due() == [] or i < 4     # 3 s round trips: the waits grow to cover them
        ack.items[0].id = i
        rel.on_ack(1, ack)
    assert 2.9 < rel.rtt[1] <= 3.0 and 5.8 < rel.first_wait(1) <= 6.0
