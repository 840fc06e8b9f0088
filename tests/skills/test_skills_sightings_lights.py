"""The exploration reads a station's light view by view: a reading carries its
confidence, a view tells its state only over a moment, and the light is settled
only by two sure views that no sure view contradicts (or that sure views
outvote by two): one sure view, however sure, settles nothing alone; every
view's verdict goes to the team server with its confidence and its view number."""
from types import SimpleNamespace

from rll_bt import rules
from rll_bt.backend import Detections, LightDetection, Pose2D
from skills.exploration.light_views import LightViews
from skills.exploration.sightings import LIGHT_WINDOW, SightingCollector


class Feed:
    def __init__(self):
        self.next = None

    def detections(self):
        return self.next


def collector():
    prof = rules.profile("rcll2016")
    feed = Feed()
    where = {"pose": Pose2D(0, 0, 0)}
    sent = []
    ctx = SimpleNamespace(profile=prof, tags=feed, pose=lambda: where["pose"], estimate=lambda: None,
                          machines=SimpleNamespace(observe=sent.append))
    tag = prof.tag_ids("C-CS1")[0]
    c = SightingCollector(ctx)
    c.where, c.sent = where, sent
    return c, feed, tag


def probs(state, p):
    """The light network's answer: ``p`` for ``state``, the rest spread over the others."""
    return tuple(p if s == state else (1.0 - p) / 7 for s in range(8))


def read(c, feed, tag, t, state, p=0.995, at=None):
    if at is not None:
        c.where["pose"] = Pose2D(at[0], at[1], 0.0)
    feed.next = Detections(t, (), (LightDetection((0, 0, 8, 33), state, p, probs(state, p), "front",
                                                  tag_id=tag),), None)
    c.look()


def test_a_sure_view_tells_its_state_only_over_a_moment():
    c, feed, tag = collector()
    read(c, feed, tag, 0.0, 5)
    read(c, feed, tag, 0.1, 5)
    read(c, feed, tag, 0.2, 5)
    assert c.light_state("C-CS1") is None            # three frames within 0.2 s: not yet a moment
    read(c, feed, tag, 0.4, 5)
    last = c.sent[-1]
    assert (last.light_state, last.light_view) == (5, 1) and last.light_confidence >= 0.99
    assert c.light_state("C-CS1") is None and c.light_unsure("C-CS1")   # one sure view: read again
    for i in range(4):                                # from another place
        read(c, feed, tag, 1.0 + 0.2 * i, 5, at=(0.5, 0.0))
    assert c.light_state("C-CS1") == 5 and c.sent[-1].light_view == 2


def test_a_reading_below_its_confidence_is_not_settled_but_read_again_from_a_second_view():
    c, feed, tag = collector()
    for i in range(6):                                # a wrong answer, unsure (0.8 < 0.9)
        read(c, feed, tag, 0.2 * i, 4, p=0.8, at=(0.0, 0.0))
    assert c.light_state("C-CS1") is None and c.light_unsure("C-CS1")
    assert c.sent[-1].light_state == 4 and c.sent[-1].light_confidence < 0.9   # told, as unsure
    for i in range(6):                                # 0.45 m sideways: another view, the right answer
        read(c, feed, tag, 2.0 + 0.2 * i, 5, p=0.95, at=(0.0, 0.45))
    assert c.views.current_view("C-CS1") == 2
    assert c.light_state("C-CS1") is None             # one confident view is not enough
    for i in range(6):                                # a third view agrees, and is sure
        read(c, feed, tag, 4.0 + 0.2 * i, 5, p=0.995, at=(0.0, -0.45))
    assert c.light_state("C-CS1") is None             # one sure view is not enough either
    for i in range(6):                                # a fourth, sure too
        read(c, feed, tag, 6.0 + 0.2 * i, 5, p=0.995, at=(0.5, -0.45))
    assert c.light_state("C-CS1") == 5 and not c.light_unsure("C-CS1")
    assert [o.light_view for o in c.sent if o.light_view is not None][-1] == 4


def test_confident_views_of_one_robot_that_agree_do_not_settle_without_a_sure_one():
    # what one robot driving past RS2 read in a rendered game: the green lamp unlit, three times
    v = LightViews()
    for k, p in enumerate((0.953, 0.969, 0.983)):
        for i in range(5):
            v.add("M-RS2", 5.0 * k + 0.2 * i, 4, probs(4, p), (0.5 * k, 0.0))
    assert v.views("M-RS2") == 3 and v.settled("M-RS2") is None and v.unsure("M-RS2")
    for k in range(2):                                # sure views of the right state: not held back by them
        for i in range(5):
            v.add("M-RS2", 20.0 + 5.0 * k + 0.2 * i, 5, probs(5, 0.995), (3.0 + 0.5 * k, 0.0))
    assert v.settled("M-RS2") == 5


def test_confident_views_that_disagree_settle_nothing_until_outvoted():
    v = LightViews()
    for k, state in enumerate((5, 4)):
        for i in range(5):
            v.add("C-CS1", 10.0 * k + 0.2 * i, state, probs(state, 0.995), (k, 0.0))
    assert v.settled("C-CS1") is None                 # two sure views, two answers
    for i in range(5):
        v.add("C-CS1", 20.0 + 0.2 * i, 4, probs(4, 0.95), (2, 0.0))
    assert v.settled("C-CS1") is None                 # a confident view does not decide it
    for i in range(5):
        v.add("C-CS1", 30.0 + 0.2 * i, 4, probs(4, 0.995), (3, 0.0))
    assert v.settled("C-CS1") is None                 # two sure against one
    for i in range(5):
        v.add("C-CS1", 40.0 + 0.2 * i, 4, probs(4, 0.995), (4, 0.0))
    assert v.settled("C-CS1") == 4                    # three against one


def test_frames_of_one_view_that_disagree_tell_nothing_until_they_leave_the_window():
    c, feed, tag = collector()
    for i, s in enumerate([5, 5, 4, 5, 4, 5]):
        read(c, feed, tag, 0.2 * i, s)
    assert c.light_state("C-CS1") is None             # 4 of 6 agree: not enough
    t0 = LIGHT_WINDOW + 2.0                           # later: another view, even from here
    for i in range(4):
        read(c, feed, tag, t0 + 0.2 * i, 4)
    assert c.views.current_view("C-CS1") == 2
    for i in range(4):                                # and a second sure view agrees
        read(c, feed, tag, t0 + 2.0 + 0.2 * i, 4, at=(0.5, 0.0))
    assert c.light_state("C-CS1") == 4


def test_a_view_is_as_sure_as_its_frames_together():
    v = LightViews()
    for i, (state, p) in enumerate(((5, 0.999), (5, 0.999), (5, 0.999), (5, 0.999), (4, 0.8))):
        v.add("C-CS1", 0.2 * i, state, probs(state, p), (0.0, 0.0))
    verdict = v.verdict("C-CS1")
    assert verdict.state == 5 and 0.8 < verdict.confidence < 0.9     # the odd frame pulls it down
    assert v.settled("C-CS1") is None


def test_exact_readings_count_at_once():
    # oracle perception hands the refbox's state over (no class probabilities): three readings
    # in one moment tell it, as the votes always did, and go out without a view
    c, feed, tag = collector()
    for t in (0.0, 0.05, 0.1):
        feed.next = Detections(t, (), (LightDetection((0, 0, 8, 33), 3, 1.0, camera="front", tag_id=tag),), None)
        c.look()
    assert c.light_state("C-CS1") == 3
    assert c.sent[-1].light_state == 3 and c.sent[-1].light_view is None
