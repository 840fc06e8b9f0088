"""The 2017+ order schedule and delivery by order id (refbox HEAD, game.clp).

Schedule (eleven orders of quantity 1, times in seconds of a 1200 s
production):

- Complexities: five times one of {C0, C1} and one of {C2, C3} at random;
  #1 and #2, standing orders for the whole production (active from its
  start), take the first pair (#1 C0 or C1, #2 C2 or C3); the other four
  low and four high ones are shuffled over #3-#10.
- #3-#10: eight slots; slot k's window starts at U{c-90..c+90} with centre
  c = 180 + 120 (k - 3); window length C0/C1 U{90..180}, C2/C3 U{150..210};
  the order is announced ``lead`` s before its window opens, lead C0
  U{60..120}, C1 U{120..300}, C2 U{300..400}, C3 U{400..500}.  An order that
  would be announced before the exploration time is moved later (window
  too) to be announced at it, one announced after 960 s earlier to 960 s;
  a window ending after the production is shifted back to end at it.
- #11: C0 overtime order, window [P, P + overtime], competitive; one of
  #3-#10, at random, is competitive too.
- Colours: base and cap at random; rings one after another, each different
  from the one before (ring 3 may equal ring 1).  Redrawn (rings and base of
  the later order) until a standing order's first ring is a free colour and
  no two orders with rings share base and first ring.  Gate U{1..3}.

All draws are integer uniform (CLIPS ``random``).  A shorter production (a
fast test game) scales every time by P / 1200, except the exploration time,
which is the game's.

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
- late: all step points still paid, the delivery points reduced by the
  profile's graded deduction (``Profile.delivery_points``: by quarters of
  the window's length late, 18.75 % each, at most 75 %);
- a competitive order: the first team to deliver it gains
  ``competitive_first`` (+10), the second loses min(its delivery points, 10);
- plus the product: each ring by the cost of its colour (5/10/20) and the
  cap (10).
"""
from __future__ import annotations

import random

from rll_bt.rules import BASE_COLORS, CAP_COLORS, RING_COLORS, other_team

from .orders2016 import DeliveryResult, Order, placed_order, product_awards
from .world import Workpiece

#: complexity -> (lead range, window length range), globals.clp ORDER-* values
TIMES_2025 = {
    0: ((60, 120), (90, 180)),
    1: ((120, 300), (90, 180)),
    2: ((300, 400), (150, 210)),
    3: ((400, 500), (150, 210)),
}
NOMINAL_2025 = 1200
FIRST_CENTRE, CENTRE_STEP, CENTRE_SPREAD = 180, 120, 90   # ORDER-ACTIVATION-DISTANCE/-DEVIATION
ACTIVATE_LATEST = 960                                      # ORDER-ACTIVATE-LATEST-TIME


def complexities_2025(rng: random.Random, n_pairs: int = 5) -> list[int]:
    """Five pairs (one of C0/C1, one of C2/C3): the standing orders' two, then the
    other eight shuffled."""
    out = []
    for _ in range(n_pairs):
        low, high = [0, 1], [2, 3]
        rng.shuffle(low)
        rng.shuffle(high)
        out += [low[0], high[0]]
    rest = out[2:]
    rng.shuffle(rest)
    return out[:2] + rest


def ring_colors_2025(rng: random.Random, complexity: int) -> tuple[str, ...]:
    """Ring colours as randomize-ring-colors draws them: each differs from the one
    before it."""
    rings: list[str] = []
    for _ in range(complexity):
        rings.append(rng.choice([c for c in RING_COLORS if not rings or c != rings[-1]]))
    return tuple(rings)


def schedule_2025(profile, rng: random.Random, timing,
                  ring_costs: dict[str, int] | None = None) -> list[Order]:
    """The game's orders (not yet active), per the module docstring."""
    scale = timing.production_scale
    explore = float(timing.exploration_time) / scale if scale > 0 else 0.0
    shapes = list(profile.orders)
    random_ids = [i for i, s in enumerate(shapes, start=1) if not (s.standing or s.overtime)]
    cxs = complexities_2025(rng, max(1, (len(random_ids) + 2) // 2))
    draw = iter(cxs)
    orders = []
    slot = 0
    for i, shape in enumerate(shapes, start=1):
        if shape.overtime:
            cx = rng.choice(shape.complexities)
        else:
            cx = next(draw)
        if shape.standing or shape.overtime:
            start = end = activate = 0
        else:
            centre = FIRST_CENTRE + CENTRE_STEP * slot
            slot += 1
            (llo, lhi), (dlo, dhi) = TIMES_2025[cx]
            start = rng.randint(centre - CENTRE_SPREAD, centre + CENTRE_SPREAD)
            end = start + rng.randint(dlo, dhi)
            activate = max(start - rng.randint(llo, lhi), 0)
            if activate < explore:
                shift = explore - activate
                activate, start, end = activate + shift, start + shift, end + shift
            if activate > ACTIVATE_LATEST:
                shift = activate - ACTIVATE_LATEST
                activate, start, end = activate - shift, start - shift, end - shift
            if end > NOMINAL_2025:
                start, end = start - (end - NOMINAL_2025), NOMINAL_2025
        gate = rng.randint(1, 3)
        base = rng.choice(BASE_COLORS)
        rings = ring_colors_2025(rng, cx)
        cap = rng.choice(CAP_COLORS)
        orders.append(placed_order(i, shape, timing, scale, (start, end, activate),
                                   complexity=cx, base=base, rings=rings, cap=cap, gate=gate))
    competitive = [o for o in orders if o.id in random_ids and o.quantity == 1]
    if competitive:
        rng.choice(competitive).competitive = True
    _settle_colors(orders, rng, ring_costs or {})
    return orders


def _settle_colors(orders: list[Order], rng: random.Random, ring_costs: dict[str, int]) -> None:
    """Redraw rings and base until a standing order's first ring is free and no two
    orders with rings share base and first ring (the later order is redrawn)."""
    free = {c for c in RING_COLORS if ring_costs.get(c, 0) == 0}

    def conflict() -> Order | None:
        for o1 in orders:
            if o1.standing and o1.rings and o1.rings[0] not in free:
                return o1
            for o2 in orders:
                if (o1.id > o2.id and o1.rings and o2.rings and o1.base == o2.base
                        and o1.rings[0] == o2.rings[0]):
                    return o1
        return None

    for _ in range(10000):
        o = conflict()
        if o is None:
            return
        o.rings = ring_colors_2025(rng, o.complexity)
        o.base = rng.choice(BASE_COLORS)
    raise RuntimeError("no order colours satisfy the 2025 constraints")


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
    pts = profile.delivery_points(o.complexity, t, o.end, o.begin)
    if t <= o.end:
        how, reason = "in-time", f"delivered item for order {o.id}"
    else:
        how = "late"
        reason = (f"delivered item for order {o.id} ({t - o.end:.0f} s late, "
                  f"{s.delivery_by_complexity[o.complexity] - pts} deducted)")
    awards = [(pts, reason)]
    if o.competitive:
        if o.delivered[other_team(team)] > o.delivered[team]:
            awards.append((-min(pts, abs(s.competitive_second)),
                           f"second delivery for competitive order {o.id}"))
        else:
            awards.append((s.competitive_first, f"first delivery for competitive order {o.id}"))
    o.delivered[team] += 1
    return DeliveryResult(how, o.id, tuple(awards) + tuple(product_awards(profile, o, ring_costs)))
