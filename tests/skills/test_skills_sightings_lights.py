"""The exploration's light state is told only when the readings agree,
over a moment; disagreeing readings tell nothing until they leave the window."""
from types import SimpleNamespace

from rll_bt import rules
from rll_bt.backend import Detections, LightDetection, Pose2D
from skills.exploration.sightings import LIGHT_WINDOW, SightingCollector


class Feed:
    def __init__(self):
        self.next = None

    def detections(self):
        return self.next


def collector():
    prof = rules.profile("rcll2016")
    feed = Feed()
    ctx = SimpleNamespace(profile=prof, tags=feed, pose=lambda: Pose2D(0, 0, 0), estimate=lambda: None,
                          machines=SimpleNamespace(observe=lambda obs: None))
    tag = prof.tag_ids("C-CS1")[0]
    return SightingCollector(ctx), feed, tag


def read(c, feed, tag, t, state):
    feed.next = Detections(t, (), (LightDetection((0, 0, 8, 33), state, 1.0, (0.0,) * 8, "front", tag_id=tag),), None)
    c.look()


def test_agreeing_readings_over_a_moment_give_the_state():
    c, feed, tag = collector()
    read(c, feed, tag, 0.0, 5)
    read(c, feed, tag, 0.1, 5)
    read(c, feed, tag, 0.2, 5)
    assert c.light_state("C-CS1") is None            # three frames within 0.2 s: not yet a moment
    read(c, feed, tag, 0.4, 5)
    assert c.light_state("C-CS1") == 5


def test_disagreeing_readings_tell_nothing_until_they_leave_the_window():
    c, feed, tag = collector()
    for i, s in enumerate([5, 5, 4, 5, 4, 5]):
        read(c, feed, tag, 0.2 * i, s)
    assert c.light_state("C-CS1") is None            # 4 of 6 agree: not enough
    t0 = LIGHT_WINDOW + 2.0                          # another view, later
    for i in range(4):
        read(c, feed, tag, t0 + 0.2 * i, 4)
    assert c.light_state("C-CS1") == 4


def test_exact_readings_count_at_once():
    # oracle perception hands the refbox's state over (no class probabilities): three readings
    # in one moment tell it, as the votes always did
    c, feed, tag = collector()
    for t in (0.0, 0.05, 0.1):
        feed.next = Detections(t, (), (LightDetection((0, 0, 8, 33), 3, 1.0, camera="front", tag_id=tag),), None)
        c.look()
    assert c.light_state("C-CS1") == 3
