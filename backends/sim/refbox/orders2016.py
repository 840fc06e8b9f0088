"""The 2016 order schedule and delivery scoring.

Schedule (eight orders, facts.clp and game.clp of refbox tag 2016-1; shapes
from the profile, times in seconds of a 900 s production):

  ===  ====  ========  ==============  ============  ============
  id   cx    qty       window start    window length lead
  ===  ====  ========  ==============  ============  ============
  1    C0    1         0 (standing, the whole production)
  2    C0    1         U{200..400}     U{60..180}    U{120..240}
  3    C0    2         U{300..700}     U{60..180}    U{120..240}
  4    C0    1         U{700..900}     U{60..180}    U{120..240}
  5    C1    1         U{500..700}     U{90..150}    U{300..500}
  6    C2    1         U{600..720}     U{120..180}   U{480..780}
  7    C3    1         U{600..720}     U{120..180}   900
  8    C0    1         900 (overtime)  300           0
  ===  ====  ========  ==============  ============  ============

Integer uniform draws (CLIPS ``random``); a window ending after the
production is shifted back to end at it; the order is announced at
max(0, start - lead) (so the C3 is known from the first second).  A
shorter production (a fast test game) scales every time by P / 900.
Colours: base and cap at random, the rings of a C-n order n distinct colours
(the first n of a shuffled list); delivery gate U{1..3}.

Delivery (the refbox's orders.clp, by colour, with the 2016 point values):
the DS consumes a workpiece and looks for an active order with the same
base, ring sequence and cap.

- none: no points, an attention message ("invalid order delivered");
- only at another gate (the DS was prepared for a different gate; gate 0
  accepts any): ``delivery_wrong`` (1);
- the team has delivered the requested quantity already: ``delivery_wrong`` (1);
- within the window: ``delivery_by_complexity`` (20);
- after the window, less than ``delivery_late_grace`` (10 s) late:
  ``int(20 - 1.5 * floor(lateness))`` (orders.clp "15 - floor(Td - Te) * 1.5 + 5");
- later: ``delivery_too_late`` (5);
- before the window opens: 0 points and an attention message.

A delivery that counts for an order (in time, late or too late) also scores
the product: each ring by the cost of its colour (5/10/20), the pre-cap
points of its complexity (C1/C2/C3 10/30/80) and the cap (10).
"""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

from rll_bt.rules import BASE_COLORS, CAP_COLORS, CYAN, MAGENTA, RING_COLORS

from .world import Workpiece

#: order id -> (window start range, window length range, lead range), game.clp / facts.clp
TIMES_2016 = {
    1: ((0, 0), (900, 900), (900, 900)),
    2: ((200, 400), (60, 180), (120, 240)),
    3: ((300, 700), (60, 180), (120, 240)),
    4: ((700, 900), (60, 180), (120, 240)),
    5: ((500, 700), (90, 150), (300, 500)),
    6: ((600, 720), (120, 180), (480, 780)),
    7: ((600, 720), (120, 180), (900, 900)),
    8: ((900, 900), (300, 300), (0, 0)),
}
NOMINAL_2016 = 900


@dataclass
class Order:
    """One order; times are production game seconds."""

    id: int
    complexity: int
    base: str
    rings: tuple[str, ...]
    cap: str
    quantity: int
    gate: int
    begin: int
    end: int
    activate_at: int
    standing: bool = False
    overtime: bool = False
    competitive: bool = False
    active: bool = False
    delivered: dict[str, int] = field(default_factory=lambda: {CYAN: 0, MAGENTA: 0})

    def matches(self, wp: Workpiece) -> bool:
        return (wp.base == self.base and tuple(wp.rings) == self.rings and wp.cap == self.cap)

    def remaining(self, team: str) -> int:
        return self.quantity - self.delivered[team]

    def __str__(self) -> str:
        rings = "+".join(self.rings) or "-"
        return (f"#{self.id} C{self.complexity} {self.base}/{rings}/{self.cap} x{self.quantity} "
                f"gate {self.gate} [{self.begin}, {self.end}] from {self.activate_at}")


def placed_order(oid: int, shape, timing, scale: float, window: tuple[float, float, float], **product) -> Order:
    """The order of a drawn shape, its (start, end, activate) window placed in the game's production.

    An overtime order opens when production ends and lasts the overtime; a standing one spans the whole
    production from the start; any other has its drawn window scaled to this production's length."""
    P = float(timing.production)
    if shape.overtime:
        begin, end, act = int(P), int(math.ceil(P + timing.overtime)), int(P)
    elif shape.standing:
        begin, end, act = 0, int(P), 0
    else:
        begin, end, act = (int(round(v * scale)) for v in window)
    return Order(id=oid, quantity=shape.quantity, begin=begin, end=end, activate_at=act,
                 standing=shape.standing, overtime=shape.overtime, competitive=shape.competitive, **product)


def schedule_2016(profile, rng: random.Random, timing) -> list[Order]:
    """The game's orders (not yet active), per the module docstring."""
    scale = timing.production_scale
    orders = []
    for i, shape in enumerate(profile.orders, start=1):
        cx = rng.choice(shape.complexities)
        (slo, shi), (dlo, dhi), (llo, lhi) = TIMES_2016[i]
        start = rng.randint(slo, shi)
        end = start + rng.randint(dlo, dhi)
        if end > NOMINAL_2016 and not shape.overtime:
            start, end = start - (end - NOMINAL_2016), NOMINAL_2016
        activate = max(start - rng.randint(llo, lhi), 0)
        gate = rng.randint(1, 3)
        rings = tuple(rng.sample(RING_COLORS, cx))
        base, cap = rng.choice(BASE_COLORS), rng.choice(CAP_COLORS)
        orders.append(placed_order(i, shape, timing, scale, (start, end, activate),
                                   complexity=cx, base=base, rings=rings, cap=cap, gate=gate))
    return orders


@dataclass(frozen=True)
class DeliveryResult:
    """How a delivery was judged: ``how`` is one of in-time, late, too-late,
    too-soon, wrong-gate, too-many, no-order; ``awards`` are (points, reason)."""

    how: str
    order: int | None
    awards: tuple[tuple[int, str], ...]
    attention: str | None = None

    @property
    def points(self) -> int:
        return sum(p for p, _ in self.awards)


def product_awards(profile, order: Order, ring_costs: dict[str, int]) -> list[tuple[int, str]]:
    """Ring steps, pre-cap and cap points of a delivered ``order``'s product."""
    s = profile.scoring
    out = []
    for color in order.rings:
        cost = ring_costs.get(color, 0)
        out.append((s.ring_by_cost[cost], f"mounted CC{cost} ring {color} for order {order.id}"))
    if order.complexity > 0 and s.precap_by_complexity[order.complexity]:
        out.append((s.precap_by_complexity[order.complexity],
                    f"mounted last ring for C{order.complexity} order {order.id}"))
    out.append((s.cap_mounted, f"mounted cap for order {order.id}"))
    return out


def late_points_2016(profile, lateness: float) -> int:
    """Delivery points ``lateness`` game seconds after the window closed."""
    s = profile.scoring
    if lateness < s.delivery_late_grace:
        return int(s.delivery_by_complexity[0] - 1.5 * math.floor(lateness))
    return s.delivery_too_late


def judge_delivery_2016(profile, orders: list[Order], team: str, wp: Workpiece, gate: int,
                        t: float, ring_costs: dict[str, int]) -> DeliveryResult:
    """Score ``team``'s delivery of ``wp`` at DS gate ``gate`` at production time ``t``;
    updates the matched order's delivered count."""
    s = profile.scoring
    spec = [o for o in orders if o.active and o.matches(wp)]
    if not spec:
        return DeliveryResult("no-order", None, (),
                              f"Invalid order delivered by {team}: {wp}")
    at_gate = [o for o in spec if gate == 0 or o.gate == gate]
    if not at_gate:
        o = spec[0]
        return DeliveryResult("wrong-gate", o.id, ((s.delivery_wrong,
                              f"delivered item for order {o.id} (wrong delivery gate {gate}, "
                              f"expected {o.gate})"),))
    open_ = [o for o in at_gate if o.remaining(team) > 0]
    if not open_:
        o = at_gate[0]
        o.delivered[team] += 1
        return DeliveryResult("too-many", o.id, ((s.delivery_wrong,
                              f"delivered item for order {o.id} (too many)"),))
    in_window = [o for o in open_ if o.begin <= t <= o.end]
    late = [o for o in open_ if t > o.end]
    if in_window:
        o = min(in_window, key=lambda o: (-o.remaining(team), o.end, o.id))
        how, pts = "in-time", s.delivery_by_complexity[o.complexity]
        reason = f"delivered item for order {o.id}"
    elif late:
        o = max(late, key=lambda o: (o.end, -o.id))
        lateness = t - o.end
        pts = late_points_2016(profile, lateness)
        how = "late" if lateness < s.delivery_late_grace else "too-late"
        reason = f"delivered item for order {o.id} ({lateness:.0f} s late)"
    else:
        o = min(open_, key=lambda o: o.begin)
        return DeliveryResult("too-soon", o.id, ((0, f"delivered item for order {o.id} "
                                                     "(too soon, before its window)"),),
                              f"Order {o.id} delivered by {team} before its window opened")
    o.delivered[team] += 1
    return DeliveryResult(how, o.id, ((pts, reason),) + tuple(product_awards(profile, o, ring_costs)))
