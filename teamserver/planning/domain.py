"""The RCLL production domain: orders C0..C3 as task networks.

A product is a base from the base station, 0..3 rings from the ring
stations, a cap from a cap station, delivered at the delivery station:

    stage 0   = get a base of the order's colour at the BS output
    stage i   = (stage i-1  ||  additional bases for ring i on its RS slide)
                -> MountRing(ring i) -> GetWorkpiece(RS output)
    cap       = RetrieveCap(shelf -> CS input) -> GetWorkpiece(CS output)
                -> the cap-less base is discarded, or used as an additional base
    finish    = (stage k || cap) -> MountCap -> GetWorkpiece(CS output) -> Deliver

``||`` is unordered: additional bases and the cap retrieval start at once,
in parallel with the main chain, and each mount waits only for what it
needs.  A ring colour costs 0, 1 or 2 additional bases (RingInfo); each is
fetched from the BS (any colour) and put on the slide of the RS that mounts
that colour, unless the cap-less base from the cap retrieval can serve.

Steps are the team protocol's tasks (GetWorkpiece, PutWorkpiece,
RetrieveCap, MountRing, MountCap, Deliver, Discard) with the PrepareMachine
each needs and the station locks they take and release.  A step whose
robot must already hold the workpiece (PutWorkpiece, MountRing, MountCap,
Deliver, Discard) is ``carry``: it goes to the robot that made the pickup
before it (or to ``holder`` when a repair starts from a held workpiece).

The finished product is *handed over* (``hand_over``) one of two ways:

    direct        = Deliver
    via_storage   = PutWorkpiece(SS input, STORE) -> GetWorkpiece(SS output,
                    RETRIEVE, not before the window opens - retrieve_lead) -> Deliver

``via_storage`` applies only with a storage station (rcll2025) and when it
pays (:func:`storage_pays`): the product is expected ready at least
``Storage.min_wait`` seconds before its order's window opens, so a robot
would otherwise hold it (or leave it blocking the cap station's output) for
that long.  The shelf place is left open (None); the production manager
gives each product one.  A repair also starts from a finished product (in a
gripper, at a cap station's output or on the storage shelf).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..knowledge import model as M
from .htn import Domain, Par, Seq

DOMAIN = Domain("rcll-production")
CAP_LOCK = "#cap"          # suffix of a cap station's buffer lock ("C-CS1#cap")
# the role of a picked-up workpiece: the product itself, an additional base,
# or the cap-less base a cap retrieval leaves at the CS output
MAIN, EXTRA, CAPLESS = "main", "extra", "capless"


@dataclass
class Progress:
    """What already exists of a product (for repair after a failure).

    ``base``/``rings``/``cap``: the workpiece's composition, None/() when
    there is none; ``location``: where it is ("robot:<id>", "<machine>:OUTPUT").
    ``slide_credit``: our additional bases already on each RS slide for
    this product.  ``cap_ready``: the CS holding a cap retrieved for it.
    """

    base: str | None = None
    rings: tuple[str, ...] = ()
    cap: str | None = None
    location: str | None = None
    slide_credit: dict[str, int] = field(default_factory=dict)
    cap_ready: str | None = None
    stored_at: tuple[int, int] | None = None    # (shelf, slot) when on the storage shelf


@dataclass(frozen=True)
class Storage:
    """The storage station as the planner may use it for one product.

    ``machine``: the SS ("C-SS"); ``min_wait``: game seconds the finished product
    must wait for its window before storing pays (the detour through the SS costs
    robots about ``min_wait`` minus a margin); ``retrieve_lead``: the retrieval
    may start this long before the window opens; ``ready_at``: the game time the
    product is expected finished (in a gripper), None while unknown (then
    nothing is stored).
    """

    machine: str
    min_wait: float
    retrieve_lead: float = 45.0
    ready_at: float | None = None


@dataclass
class ProductionContext:
    """What the methods may look at (read-only during planning).

    ``rs_colors``: RS machine name -> the ring colours it mounts;
    ``ring_costs``: ring colour -> additional bases; ``cs_caps``: CS machine
    name -> cap colour on its shelf; ``unusable``: stations not to plan with
    (``"<RS>:SLIDE"``: only that ring station's slide; ``"<CS>:SHELF"``: no cap retrieval
    at that cap station, its shelf's carriers out of reach);
    ``ds_by_order``: True from 2017 on (DS prepared with the order id);
    ``storage``: the storage station to use where it pays, None without one.
    """

    team_prefix: str
    rs_colors: dict[str, tuple[str, ...]]
    ring_costs: dict[str, int]
    cs_caps: dict[str, str]
    order: M.Order
    progress: Progress = field(default_factory=Progress)
    unusable: frozenset[str] = frozenset()
    ds_by_order: bool = False
    reuse_capless_base: bool = True
    storage: Storage | None = None

    @property
    def bs(self) -> str:
        return f"{self.team_prefix}-BS"

    @property
    def ds(self) -> str:
        return f"{self.team_prefix}-DS"

    def rs_for(self, color: str) -> str | None:
        """The usable RS mounting ``color`` (its slide too when the colour costs bases)."""
        for rs in sorted(self.rs_colors):
            if color in self.rs_colors[rs] and rs not in self.unusable and not (
                    self.ring_costs.get(color, 0) > 0 and f"{rs}:{M.SLIDE}" in self.unusable):
                return rs
        return None

    def cs_for(self, cap: str) -> list[str]:
        return [cs for cs in sorted(self.cs_caps)
                if self.cs_caps[cs] == cap and cs not in self.unusable]


def storage_pays(ctx: ProductionContext) -> bool:
    """Store the finished product in the storage station: there is one, it is usable,
    and the product is expected ready ``min_wait`` s or more before its window opens,
    and more than ``retrieve_lead`` s (it would be retrieved again at once); with
    ``min_wait`` -inf every product (a product goes through the station once:
    :meth:`~teamserver.production.handover.Handover.redecide`)."""
    st = ctx.storage
    if st is None or st.ready_at is None or st.machine in ctx.unusable or ctx.order is None:
        return False
    wait = ctx.order.begin - st.ready_at
    return wait >= st.min_wait and (wait > st.retrieve_lead or st.min_wait == -math.inf)


def _ss_place(place) -> dict:
    shelf, slot = place if place is not None else (None, None)
    return {"shelf": shelf, "slot": slot}


def _step(kind: str, params: dict, *, prepare: dict | None = None, locks=(), releases=(),
          carry: bool = False, holder: str | None = None) -> dict:
    return {"kind": kind, "params": params, "prepare": prepare, "locks": tuple(locks),
            "releases": tuple(releases), "carry": carry, "holder": holder}


# -- operators -----------------------------------------------------------------
@DOMAIN.operator("get_base")
def op_get_base(ctx: ProductionContext, color: str, role: str = MAIN):
    if ctx.bs in ctx.unusable:
        return None
    return _step(M.GET_WORKPIECE, {"machine": ctx.bs, "side": M.OUTPUT, "base": color,
                                   "role": role},
                 prepare={"machine": ctx.bs, "bs": {"side": M.OUTPUT, "color": color}},
                 locks=(ctx.bs,), releases=(ctx.bs,))


@DOMAIN.operator("pickup")
def op_pickup(ctx: ProductionContext, machine: str, release_cap: bool = False,
              role: str = MAIN):
    """Take the workpiece from ``machine``'s output."""
    releases = (machine, machine + CAP_LOCK) if release_cap else (machine,)
    return _step(M.GET_WORKPIECE, {"machine": machine, "side": M.OUTPUT, "role": role},
                 locks=(machine,), releases=releases)


@DOMAIN.operator("put_slide")
def op_put_slide(ctx: ProductionContext, rs: str, holder: str | None = None):
    return _step(M.PUT_WORKPIECE, {"machine": rs, "side": M.SLIDE}, carry=True, holder=holder)


@DOMAIN.operator("mount_ring")
def op_mount_ring(ctx: ProductionContext, rs: str, color: str, holder: str | None = None):
    if color not in ctx.rs_colors.get(rs, ()):
        return None
    return _step(M.MOUNT_RING, {"machine": rs, "ring_color": color,
                                "cost": ctx.ring_costs.get(color, 0)},
                 prepare={"machine": rs, "rs": {"ring_color": color}},
                 locks=(rs,), carry=True, holder=holder)


@DOMAIN.operator("retrieve_cap")
def op_retrieve_cap(ctx: ProductionContext, cs: str):
    if f"{cs}:{M.SHELF}" in ctx.unusable:
        return None
    return _step(M.RETRIEVE_CAP, {"machine": cs, "cap": ctx.cs_caps[cs]},
                 prepare={"machine": cs, "cs": {"operation": "RETRIEVE_CAP"}},
                 locks=(cs, cs + CAP_LOCK))


@DOMAIN.operator("mount_cap")
def op_mount_cap(ctx: ProductionContext, cs: str, holder: str | None = None):
    return _step(M.MOUNT_CAP, {"machine": cs, "cap_color": ctx.cs_caps[cs]},
                 prepare={"machine": cs, "cs": {"operation": "MOUNT_CAP"}},
                 locks=(cs, cs + CAP_LOCK), carry=True, holder=holder)


@DOMAIN.operator("deliver")
def op_deliver(ctx: ProductionContext, holder: str | None = None):
    if ctx.ds in ctx.unusable:
        return None
    o = ctx.order
    target = {"order_id": o.id} if ctx.ds_by_order else {"gate": o.gate}
    return _step(M.DELIVER, {"machine": ctx.ds, "order_id": o.id, "not_before": o.begin,
                             **target},
                 prepare={"machine": ctx.ds, "ds": dict(target)},
                 locks=(ctx.ds,), releases=(ctx.ds,), carry=True, holder=holder)


@DOMAIN.operator("store")
def op_store(ctx: ProductionContext, holder: str | None = None):
    """Put the finished product into the storage station (STORE at a shelf place the
    production manager fills in)."""
    ss = ctx.storage.machine
    return _step(M.PUT_WORKPIECE, {"machine": ss, "side": M.INPUT, "store": True},
                 prepare={"machine": ss, "ss": {"operation": "STORE", **_ss_place(None)}},
                 locks=(ss,), releases=(ss,), carry=True, holder=holder)


@DOMAIN.operator("retrieve")
def op_retrieve(ctx: ProductionContext, place: tuple[int, int] | None = None):
    """Take the stored product from the storage station's output (RETRIEVE), not before
    ``retrieve_lead`` s before the window opens."""
    st = ctx.storage
    if st is None:
        return None
    return _step(M.GET_WORKPIECE, {"machine": st.machine, "side": M.OUTPUT, "role": MAIN,
                                   "not_before": max(ctx.order.begin - st.retrieve_lead, 0.0)},
                 prepare={"machine": st.machine, "ss": {"operation": "RETRIEVE",
                                                        **_ss_place(place)}},
                 locks=(st.machine,), releases=(st.machine,))


@DOMAIN.operator("discard")
def op_discard(ctx: ProductionContext, holder: str | None = None):
    return _step(M.DISCARD, {}, carry=True, holder=holder)


# -- methods ---------------------------------------------------------------------
@DOMAIN.method("product")
def m_product(ctx: ProductionContext):
    """Make ctx.order from what exists (nothing, or a partial workpiece)."""
    o, pr = ctx.order, ctx.progress
    if pr.base is not None and (pr.base != o.base or tuple(pr.rings) != tuple(o.rings)[
            :len(pr.rings)]):
        return None                     # the workpiece cannot become this product
    if pr.cap is not None:
        if pr.cap == o.cap and tuple(pr.rings) == tuple(o.rings):
            yield _finished_spec(ctx)   # only to be handed over
        return None
    stations = [ctx.rs_for(c) for c in o.rings[len(pr.rings):]]
    if any(rs is None for rs in stations):
        return None
    caps = ctx.cs_for(o.cap)
    if pr.cap_ready is not None:
        caps = [pr.cap_ready] if pr.cap_ready in caps else []
    for cs in caps:
        yield ("product_with", cs)


@DOMAIN.method("product_with", "reuse_capless_base")
def m_product_reuse(ctx: ProductionContext, cs: str):
    """The cap-less base from the cap retrieval serves as an additional base for the
    last ring, if that one needs one: the cap is then retrieved while the ring before
    is mounted.  (For an earlier ring the retrieved cap would keep the cap station
    from every other product for several ring mounts.)"""
    pr = ctx.progress
    if not ctx.reuse_capless_base or pr.cap_ready is not None:
        return None
    remaining = ctx.order.rings[len(pr.rings):]
    if remaining and _bases_needed(ctx, remaining, len(remaining) - 1) > 0:
        return _product_spec(ctx, cs, reuse_for=len(remaining) - 1)
    return None


@DOMAIN.method("product_with", "discard_capless_base")
def m_product_discard(ctx: ProductionContext, cs: str):
    return _product_spec(ctx, cs, reuse_for=None)


def _bases_needed(ctx: ProductionContext, remaining, i: int) -> int:
    """Additional bases still to bring for remaining ring i (after slide credit)."""
    credit = dict(ctx.progress.slide_credit)
    for j in range(i + 1):
        rj = ctx.rs_for(remaining[j])
        cost = ctx.ring_costs.get(remaining[j], 0)
        use = min(cost, credit.get(rj, 0))
        credit[rj] = credit.get(rj, 0) - use
        if j == i:
            return cost - use
    return 0


def _product_spec(ctx: ProductionContext, cs: str, reuse_for: int | None):
    pr = ctx.progress
    remaining = ctx.order.rings[len(pr.rings):]
    holder = pr.location[len("robot:"):] if pr.location and pr.location.startswith(
        "robot:") else None
    # stage 0: the workpiece to start from
    if pr.base is None:
        chain = ("get_base", ctx.order.base)
    elif holder is not None:
        chain = None                    # already in a gripper
    else:
        chain = ("pickup", pr.location.split(":")[0])
    for i, color in enumerate(remaining):
        rs = ctx.rs_for(color)
        need = _bases_needed(ctx, remaining, i)
        extras = []
        if reuse_for == i and need > 0:
            extras.append(Seq(("retrieve_cap", cs), ("pickup", cs, False, CAPLESS),
                              ("put_slide", rs)))
            need -= 1
        extras += [Seq(("get_base", _any_base(ctx), EXTRA), ("put_slide", rs))
                   for _ in range(need)]
        mount_holder = holder if chain is None else None
        chain = Seq(Par(chain, *extras) if chain else Par(*extras),
                    ("mount_ring", rs, color, mount_holder), ("pickup", rs))
    if pr.cap_ready is not None or reuse_for is not None:
        cap = None
    else:
        cap = Seq(("retrieve_cap", cs), ("pickup", cs, False, CAPLESS), ("discard",))
    cap_holder = holder if chain is None else None
    parts = [p for p in (chain, cap) if p]
    return Seq(Par(*parts), ("mount_cap", cs, cap_holder), ("pickup", cs, True), ("hand_over",))


def _finished_spec(ctx: ProductionContext):
    """Hand over a finished product from where it is."""
    pr = ctx.progress
    machine, _, side = (pr.location or "").partition(":")
    if machine == "robot":
        return ("hand_over", side)
    if side == M.SHELF:
        return Seq(("retrieve", pr.stored_at), ("deliver",))
    return Seq(("pickup", machine, True), ("hand_over",))


@DOMAIN.method("hand_over", "via_storage")
def m_hand_over_stored(ctx: ProductionContext, holder: str | None = None):
    """Store the product until shortly before its window opens (when that pays)."""
    if not storage_pays(ctx):
        return None
    return Seq(("store", holder), ("retrieve",), ("deliver",))


@DOMAIN.method("hand_over", "direct")
def m_hand_over_direct(ctx: ProductionContext, holder: str | None = None):
    return ("deliver", holder)


def _any_base(ctx: ProductionContext) -> str:
    """Colour of an additional base: any will do; the order's own saves a prepare change."""
    return ctx.order.base
