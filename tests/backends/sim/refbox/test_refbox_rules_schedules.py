"""Order schedules and down periods drawn as the real refbox draws them (refbox-rules.md:
facts.clp / game.clp of tag 2016-1, game.clp / globals.clp of today's master), checked
over thousands of draws against the ranges and the probabilities they imply."""
from __future__ import annotations

import math
import random
from collections import Counter
from statistics import mean

import pytest

from backends.sim.refbox import Rules2016, Rules2025, Timing
from backends.sim.refbox.orders2016 import schedule_2016
from backends.sim.refbox.orders2025 import schedule_2025
from rll_bt.rules import RING_COLORS, profile

P16, P25 = profile("rcll2016"), profile("rcll2025")
N = 3000


def within(observed: float, expected: float, sd: float, n: int, sigmas: float = 4.0) -> bool:
    """``observed`` (a mean of ``n`` draws) is within ``sigmas`` standard errors."""
    return abs(observed - expected) <= sigmas * sd / math.sqrt(n)


def u_mean_sd(lo: int, hi: int) -> tuple[float, float]:
    """Mean and standard deviation of an integer uniform U{lo..hi}."""
    k = hi - lo + 1
    return (lo + hi) / 2, math.sqrt((k * k - 1) / 12)


def p_at_least(a: tuple[int, int], b: tuple[int, int]) -> float:
    """P(Y >= X) for independent integer uniforms X ~ U{a}, Y ~ U{b}."""
    xs, ys = range(a[0], a[1] + 1), range(b[0], b[1] + 1)
    return sum(1 for x in xs for y in ys if y >= x) / (len(xs) * len(ys))


@pytest.fixture(scope="module")
def schedules16():
    rng = random.Random(2016)
    timing = Timing.from_profile(P16)
    return [{o.id: o for o in schedule_2016(P16, rng, timing)} for _ in range(N)]


@pytest.fixture(scope="module")
def schedules25():
    rng = random.Random(2025)
    timing = Timing.from_profile(P25)
    out = []
    for _ in range(N // 2):
        _rs, costs = P25.ring_setup(rng)
        out.append(({o.id: o for o in schedule_2025(P25, rng, timing, costs)}, costs))
    return out


# -- 2016 ---------------------------------------------------------------------------------

def test_2016_order_schedule_shapes_and_ranges(schedules16):
    for s in schedules16[:500]:
        assert [s[i].complexity for i in range(1, 9)] == [0, 0, 0, 0, 1, 2, 3, 0]
        assert [s[i].quantity for i in range(1, 9)] == [1, 1, 2, 1, 1, 1, 1, 1]
        assert (s[1].begin, s[1].end, s[1].activate_at) == (0, 900, 0)
        assert (s[8].begin, s[8].end, s[8].activate_at) == (900, 1200, 900)
        assert s[7].activate_at == 0                          # the C3 is known from the start
        for i, (b, length, lead) in {2: ((200, 400), (60, 180), (120, 240)),
                                     3: ((300, 700), (60, 180), (120, 240)),
                                     4: ((700, 900), (60, 180), (120, 240)),
                                     5: ((500, 700), (90, 150), (300, 500)),
                                     6: ((600, 720), (120, 180), (480, 780))}.items():
            o = s[i]
            assert length[0] <= o.end - o.begin <= length[1] and o.end <= 900
            assert b[0] <= o.begin <= b[1] or o.end == 900             # shifted back to 900
            assert o.activate_at == 0 or lead[0] <= o.begin - o.activate_at <= lead[1]


def test_2016_windows_leads_and_announcements_match_the_real_distributions(schedules16):
    n = len(schedules16)
    for i, length in {2: (60, 180), 5: (90, 150), 6: (120, 180), 7: (120, 180)}.items():
        m, sd = u_mean_sd(*length)
        assert within(mean(s[i].end - s[i].begin for s in schedules16), m, sd, n)
    m, sd = u_mean_sd(600, 720)
    assert within(mean(s[6].begin for s in schedules16), m, sd, n)
    # the C2 is announced at once when its lead (U{480..780}) reaches back past 0
    p = p_at_least((600, 720), (480, 780))
    seen = sum(s[6].activate_at == 0 for s in schedules16) / n
    assert abs(seen - p) <= 4 * math.sqrt(p * (1 - p) / n)
    # C1: activation = start - U{300..500}, never clipped (start >= 500)
    m, sd = u_mean_sd(300, 500)
    assert within(mean(s[5].begin - s[5].activate_at for s in schedules16), m, sd, n)
    # #4's window (start U{700..900}) is shifted back to end at 900 most of the time
    assert sum(s[4].end == 900 for s in schedules16) / n > 0.5


def test_2016_down_periods_over_the_whole_production():
    rng, timing, rules = random.Random(7), Timing.from_profile(P16), Rules2016()
    starts, lengths = [], []
    for _ in range(N):
        for m, (a, b) in rules.down_periods(P16, rng, timing).items():
            if m.startswith("C-"):
                starts.append(a)
                lengths.append(b - a)
                assert 30 <= b - a <= 120 and a >= 1 and b <= 900 and a == int(a)
    m, sd = u_mean_sd(30, 120)
    assert within(mean(lengths), m, sd, len(lengths))
    # the whole game: early and late starts happen (U{1 .. 900 - length})
    assert min(starts) < 10 and max(starts) > 850
    assert 0.07 < sum(a < 90 for a in starts) / len(starts) < 0.13


# -- 2025 ---------------------------------------------------------------------------------

def test_2025_exactly_four_low_and_four_high_complexities(schedules25):
    counts = Counter()
    for s, _ in schedules25:
        assert s[1].complexity in (0, 1) and s[2].complexity in (2, 3) and s[11].complexity == 0
        mid = [s[i].complexity for i in range(3, 11)]
        assert sum(c < 2 for c in mid) == 4 and sum(c >= 2 for c in mid) == 4
        counts.update(mid)
    n = 8 * len(schedules25)
    for cx in range(4):                                # each a quarter of #3-#10
        assert abs(counts[cx] / n - 0.25) < 0.02


def test_2025_windows_activation_and_competitive_orders(schedules25):
    comp = Counter()
    for s, _ in schedules25:
        assert (s[1].begin, s[1].end, s[1].activate_at) == (0, 1200, 0)
        assert (s[11].begin, s[11].end, s[11].activate_at) == (1200, 1500, 1200)
        assert s[11].competitive and not (s[1].competitive or s[2].competitive)
        ids = [i for i in range(3, 11) if s[i].competitive]
        assert len(ids) == 1
        comp.update(ids)
        for i in range(3, 11):
            o = s[i]
            assert 180 <= o.activate_at <= 960 and o.activate_at <= o.begin
            assert o.end <= 1200
            lo, hi = (90, 180) if o.complexity < 2 else (150, 210)
            assert lo <= o.end - o.begin <= hi
    n = len(schedules25)
    assert all(abs(comp[i] / n - 1 / 8) < 0.04 for i in range(3, 11))


def test_2025_window_lengths_and_leads_match_the_real_distributions(schedules25):
    lengths = {0: [], 2: []}
    leads = {cx: [] for cx in range(4)}
    for s, _ in schedules25:
        for i in range(3, 11):
            o = s[i]
            lengths[0 if o.complexity < 2 else 2].append(o.end - o.begin)
            # an unshifted order: announced lead s before its window
            if 180 < o.activate_at < 960 and o.end < 1200:
                leads[o.complexity].append(o.begin - o.activate_at)
    for key, rng_ in ((0, (90, 180)), (2, (150, 210))):
        m, sd = u_mean_sd(*rng_)
        assert within(mean(lengths[key]), m, sd, len(lengths[key]))
    for cx, rng_ in {0: (60, 120), 1: (120, 300), 2: (300, 400), 3: (400, 500)}.items():
        assert min(leads[cx]) >= rng_[0] and max(leads[cx]) <= rng_[1]
        m, sd = u_mean_sd(*rng_)
        assert within(mean(leads[cx]), m, sd, len(leads[cx]), sigmas=5)


def test_2025_slot_windows_open_around_their_centres(schedules25):
    """Slot k (#3 + k) opens at U{c-90..c+90}, c = 180 + 120 k, unless moved."""
    for k in range(4, 7):                  # slots no shift touches much
        begins = [s[3 + k].begin for s, _ in schedules25
                  if 180 < s[3 + k].activate_at < 960 and s[3 + k].end < 1200]
        m, sd = u_mean_sd(180 + 120 * k - 90, 180 + 120 * k + 90)
        assert abs(mean(begins) - m) < 12, k


def test_2025_ring_colours_follow_the_real_constraints(schedules25):
    third_is_first = total_c3 = 0
    for s, costs in schedules25:
        free = {c for c in RING_COLORS if costs[c] == 0}
        firsts = {}
        for o in s.values():
            assert all(a != b for a, b in zip(o.rings, o.rings[1:]))   # consecutive differ
            if o.standing and o.rings:
                assert o.rings[0] in free                              # standing: free first ring
            if o.rings:
                key = (o.base, o.rings[0])
                assert key not in firsts, (o.id, firsts.get(key))      # base + first ring unique
                firsts[key] = o.id
            if o.complexity == 3:
                total_c3 += 1
                third_is_first += o.rings[2] == o.rings[0]
    # ring 3 is drawn among the three colours other than ring 2: one of them is ring 1
    assert abs(third_is_first / total_c3 - 1 / 3) < 0.05


def test_2025_down_periods_after_the_exploration_time():
    rng, timing, rules = random.Random(9), Timing.from_profile(P25), Rules2025()
    starts = []
    for _ in range(N):
        for m, (a, b) in rules.down_periods(P25, rng, timing).items():
            if m.startswith("C-"):
                starts.append(a)
                assert 30 <= b - a <= 60 and a >= 180 and b <= 1200
    assert min(starts) < 190 and max(starts) > 1130        # up to 1200 - length
