"""The 2017+ order schedule and delivery by order id (refbox HEAD).

Schedule (eleven orders, shapes from the profile, refbox-protocol §4 "Orders"):

- #1 and #2: standing orders for the whole production, window [0, P],
  active from its start; #1 is C0 or C1, #2 is C2 or C3.
- #3-#10: a random complexity each; window length D, window start B and a
  lead time L (the order becomes active L seconds before its window opens)
  drawn per complexity (game seconds of a 1200 s production; our choice,
  the refbox randomises similarly):

  ====  ==========  ==================  =========
  cx    D           earliest B          L
  ====  ==========  ==================  =========
  C0    150-300     240                 60-150
  C1    180-330     360                 150-300
  C2    210-360     480                 240-400
  C3    240-360     600                 300-450
  ====  ==========  ==================  =========

  with B uniform in [earliest, P - D].  None becomes active before the
  exploration time: activation is max(exploration time, B - L), and the
  window never opens before the activation.  A shorter production scales
  D, B and L by P / 1200 (the exploration time is not scaled).
- #11: C0 overtime order, window [P, P + overtime], competitive.
- One of #3-#10, chosen at random, is competitive as well.
- Colours: base from BASE_*, cap from CAP_*, C-n rings n distinct colours;
  delivery gate 1-3; quantity 1.

Delivery: the DS is prepared with an order id (0: consume the workpiece,
no points) and the gate comes from the order.  The simulated referee
confirms a delivery when the workpiece matches the order (base, rings in
order, cap) and rejects it otherwise (no points, an attention message), as
a real referee would with ConfirmDelivery.  A confirmed delivery is judged
like orders.clp:

- the order is not active: no points, an attention message;
- the team has delivered the requested quantity already: ``delivery_wrong``;
- before the window opens: 0 points;
- within the window: ``delivery_by_complexity`` (C0/C1/C2/C3 20/30/50/100);
- late: the profile's late deduction (``Profile.delivery_points``), after
  the grace time ``delivery_too_late`` (5);
- a competitive order: the first team to deliver it gains
  ``competitive_first`` (+10), the second loses min(its delivery points, 10);
- plus the product: each ring by the cost of its colour (5/10/20) and the
  cap (10).
"""
from __future__ import annotations

import math
import random

from rll_bt.rules import other_team

from .orders2016 import DeliveryResult, Order, build_schedule, product_awards
from .world import Workpiece

#: complexity -> (window length range, earliest window start, lead time range), 1200 s game
WINDOWS_2025 = {
    0: ((150, 300), 240, (60, 150)),
    1: ((180, 330), 360, (150, 300)),
    2: ((210, 360), 480, (240, 400)),
    3: ((240, 360), 600, (300, 450)),
}


def schedule_2025(profile, rng: random.Random, timing) -> list[Order]:
    """The game's orders (not yet active), per the module docstring."""
    P = float(timing.production)
    scale = timing.production_scale
    explore = float(timing.exploration_time)
    random_ids = [i for i, s in enumerate(profile.orders, start=1)
                  if not (s.standing or s.overtime)]
    extra_competitive = (rng.choice(random_ids),) if random_ids else ()

    def window(cx: int) -> tuple[int, int, int]:
        (dlo, dhi), earliest, (llo, lhi) = WINDOWS_2025[cx]
        dur = rng.uniform(dlo, dhi) * scale
        lo = earliest * scale
        begin = rng.uniform(lo, max(lo, P - dur))
        act = min(P, max(explore, begin - rng.uniform(llo, lhi) * scale))
        end = min(P, max(begin, act) + dur)
        act_s = int(math.ceil(act))
        begin_s = max(int(begin), act_s)
        return begin_s, max(int(math.ceil(end)), begin_s), act_s
    return build_schedule(profile, rng, timing, window, extra_competitive)


def judge_delivery_2025(profile, orders: list[Order], team: str, wp: Workpiece,
                        order_id: int | None, t: float,
                        ring_costs: dict[str, int]) -> DeliveryResult:
    """Score ``team``'s delivery of ``wp`` for ``order_id`` at production time ``t``;
    updates the order's delivered count."""
    s = profile.scoring
    if not order_id:
        return DeliveryResult("consumed", None, ())
    o = next((o for o in orders if o.id == order_id), None)
    if o is None or not o.active:
        return DeliveryResult("no-order", order_id, (),
                              f"Invalid order delivered by {team}: no active order with ID "
                              f"{order_id}")
    if not o.matches(wp):
        return DeliveryResult("wrong-product", o.id, (),
                              f"Incorrect delivery for order {o.id} by {team}: {wp}")
    if o.remaining(team) <= 0:
        o.delivered[team] += 1
        return DeliveryResult("too-many", o.id, ((s.delivery_wrong, f"delivered item for order "
                                                                     f"{o.id} (too many)"),))
    if t < o.begin:
        return DeliveryResult("too-soon", o.id, ((0, f"delivered item for order {o.id} (too soon, "
                                                     "before its window)"),),
                              f"Order {o.id} delivered by {team} before its window opened")
    pts = profile.delivery_points(o.complexity, t, o.end)
    if t <= o.end:
        how, reason = "in-time", f"delivered item for order {o.id}"
    else:
        how = "late" if t - o.end <= s.delivery_late_grace else "too-late"
        reason = f"delivered item for order {o.id} ({t - o.end:.0f} s late)"
    awards = [(pts, reason)]
    if o.competitive:
        if o.delivered[other_team(team)] > o.delivered[team]:
            awards.append((-min(pts, abs(s.competitive_second)),
                           f"second delivery for competitive order {o.id}"))
        else:
            awards.append((s.competitive_first, f"first delivery for competitive order {o.id}"))
    o.delivered[team] += 1
    return DeliveryResult(how, o.id, tuple(awards) + tuple(product_awards(profile, o, ring_costs)))
