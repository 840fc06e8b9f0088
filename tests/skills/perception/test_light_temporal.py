import pytest

from skills.perception.light.temporal import BLINK, OFF, ON, UNKNOWN, LightFilter


def feed(f, states, dt=0.1, t0=0.0):
    for i, s in enumerate(states):
        f.add(t0 + i * dt, s)


def test_steady_lights():
    f = LightFilter()
    feed(f, [5] * 20)                      # red + green
    p = f.pattern()
    assert (p.green, p.yellow, p.red) == (ON, OFF, ON)
    assert p.steady_state == 5


def test_blinking_green_with_steady_yellow():
    f = LightFilter()
    # 2 Hz blink sampled at 10 Hz: 2-3 frames on, 2-3 off
    seq = [(2 | (1 if (i // 2.5) % 2 == 0 else 0)) for i in range(20)]
    feed(f, seq)
    p = f.pattern()
    assert (p.green, p.yellow, p.red) == (BLINK, ON, OFF)
    assert p.steady_state is None and p.complete


def test_unknown_until_window_is_long_enough():
    f = LightFilter(min_span=1.0)
    feed(f, [1] * 5)                       # 0.4 s
    assert f.pattern().green == UNKNOWN
    feed(f, [1] * 10, t0=0.5)
    assert f.pattern().green == ON


def test_one_bad_frame_does_not_make_a_blink():
    f = LightFilter()
    feed(f, [4] * 9 + [0] + [4] * 10)
    assert f.pattern().red == ON
    g = LightFilter()
    feed(g, [4] * 10 + [0] * 10)           # switched off once: neither steady nor blinking
    assert g.pattern().red == UNKNOWN


def test_old_frames_leave_the_window_and_bad_input():
    f = LightFilter(window=1.0, min_span=0.5)
    feed(f, [7] * 10)
    feed(f, [0] * 15, t0=2.0)
    assert f.pattern().steady_state == 0
    with pytest.raises(ValueError):
        f.add(10.0, 9)
    f.add(0.0, 1)                          # time went backwards: restart
    assert f.pattern().green == UNKNOWN


def test_a_blink_at_the_game_cameras_rate_and_one_odd_frame_among_few():
    """At 5 frames a second (a game's camera) a 2 Hz blink is still a blink;
    with frames missing (unsure readings left out), one odd frame among six
    is not."""
    f = LightFilter()
    feed(f, [4 | (1 if (i * 0.2) % 0.5 < 0.25 else 0) for i in range(10)], dt=0.2)
    p = f.pattern()
    assert (p.green, p.yellow, p.red) == (BLINK, OFF, ON)
    g = LightFilter()
    for t, s in ((0.0, 1), (0.3, 1), (0.7, 0), (1.0, 1), (1.4, 1), (1.8, 1)):
        g.add(t, s)
    assert g.pattern().green != BLINK


def _answer(state, p=0.97, other=None, q=0.0):
    """The light network's probabilities: ``p`` on ``state``, ``q`` on ``other``, the rest spread."""
    rest = (1.0 - p - q) / (7 if other is None else 6)
    return [p if s == state else q if s == other else rest for s in range(8)]


def test_a_blink_is_decided_over_the_window_and_holds_over_frames_a_lamp_is_read_unsure_in():
    """Green blinks at 2 Hz beside a steady red, 10 frames a second; every fourth
    frame the network half sees red dark (red on with probability 0.4).  Taken
    frame by frame that is a red lamp off a quarter of the time: a blink.  Taken
    light by light, the unsure frames leave red out and keep green: red ON, green BLINK."""
    f, blind = LightFilter(), LightFilter()
    for i in range(20):
        t = 0.1 * i
        green = 1 if (i // 2.5) % 2 == 0 else 0
        if i % 4 == 3:
            state, probs = green, _answer(green, 0.58, green | 4, 0.4)     # red read off, unsure
        else:
            state, probs = green | 4, _answer(green | 4)
        f.add(t, state, probs)
        blind.add(t, state)
        if i == 4:
            assert f.pattern().green == UNKNOWN                           # not from a few frames
    p = f.pattern()
    assert (p.green, p.yellow, p.red) == (BLINK, OFF, ON)
    assert blind.pattern().red != ON                                      # frame by frame: red lost
