"""Additional bases on the ring stations' slides, as the refbox counts them.

A ring colour that costs bases takes them from the ring station's slide
when its ring is mounted; with too few there the station breaks and the
workpiece inside (with its rings) is lost.  The plan puts enough bases on
the slide, but a base can miss it (a robot reports the put done while the
base fell beside the slide) and another product's mount may take ours.
So

- a ring mount is sent only while the slide holds what its colour costs
  (``loaded_with`` of MachineInfo, :meth:`Slides.slide_ready`), and a
  base is put on a slide only while it has room (:data:`SLIDE_MAX`; one
  more breaks the station);
- a mount whose bases are all put but missing from the slide for
  ``settle`` seconds gets the missing ones fetched from the BS
  (:meth:`Slides.top_up_slides`), as does a mount that waits for nothing
  else while its own bases to come are not under way (a cap-less base whose
  cap retrieval has not begun);
- a mount whose slide already holds what it costs (bases other products
  discarded there) no longer waits for its own bases that the full slide
  cannot take (:meth:`Slides.waive_full_slide_puts`): they go on the slide
  once the mount has used some.  It still waits for what the put waited
  for (the pickup of the base, and so the cap retrieval that freed a
  cap-less base): the product's cap mount, after the ring, must find the
  cap in its station (a MOUNT_CAP prepared without one breaks it).  Else the
  mount waited for puts that waited for the mount, and the robots holding its
  workpiece and its bases stood still for the rest of the game (rcll2016 seed
  10: from 540 s to the end);
- a mount that waits for nothing but the puts of its own bases, while its
  slide holds what it costs beyond the bases other waiting mounts put there,
  waits for none of them (:meth:`Slides.waive_stocked_puts`): they go on the
  slide after it, and the cap-less base's pickup (so the cap retrieval) is
  waited for by the product's cap mount instead.
"""
from __future__ import annotations

import logging

from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..planning.domain import CAPLESS, EXTRA
from .health import StationHealth
from .products import Products
from .reach import Reach

log = logging.getLogger("teamserver.production")


#: bases a slide holds at most; one more breaks the ring station (the refbox's
#: LOADED-WITH-MAX)
SLIDE_MAX = 3


class Slides:
    """Ring station slides of our team (``prefix``).  ``settle``: seconds after the
    last put before a short slide is topped up."""

    def __init__(self, kb: KnowledgeBase, products: Products, *, prefix: str, clock=None,
                 settle: float = 6.0, health: StationHealth | None = None):
        self.kb = kb
        self.health = health
        self.products = products
        self.prefix = prefix
        self.clock = clock
        self.settle = settle
        self.reach = Reach(kb)

    def slide_ready(self, task: M.Task) -> bool:
        """May ``task`` go now as far as slides are concerned?  A ring mount when the
        slide holds what its ring costs; a put on a slide while the slide, with the
        puts already under way, has room."""
        st = self.kb.stations.get(task.machine or "")
        if st is None:
            return True
        if task.kind == M.MOUNT_RING:
            cost = int(task.params.get("cost", 0))
            return cost <= 0 or st.loaded_with >= cost
        if task.kind == M.PUT_WORKPIECE and task.params.get("side") == M.SLIDE:
            return self.room(task.machine, task.id) > 0
        return True

    def room(self, machine: str, but: int | None = None) -> int:
        """Bases ``machine``'s slide still takes, the puts and discards already going
        there (but task ``but``) counted, and the puts whose base a robot holds or is
        fetching: their place is kept.  (rcll2025 seed 10 with 20 % loss: a
        cap-less base discarded there took the last place while a robot fetched a
        base for that slide, and that robot held it 380 s.)"""
        st = self.kb.stations.get(machine)
        mine = self.kb.tasks.get(but) if but is not None else None
        kept_by_me = mine is not None and self._kept(mine)
        going = 0
        for t in self.kb.open_tasks():
            if (t.id == but or t.kind not in (M.PUT_WORKPIECE, M.DISCARD) or t.machine != machine
                    or t.params.get("side") != M.SLIDE):
                continue
            if t.state == M.ASSIGNED:
                going += 1
            elif self._kept(t):                 # among kept places, the older put first
                going += not kept_by_me or t.id < but
        return SLIDE_MAX - (st.loaded_with if st is not None else 0) - going

    def _kept(self, task: M.Task) -> bool:
        """Does pending put ``task`` keep its place on the slide (its base held or
        being fetched)?"""
        if task.state != M.PENDING or task.kind != M.PUT_WORKPIECE:
            return False
        src = self.kb.tasks.get(task.params.get("carry_from"))
        return src is not None and src.state in (M.ASSIGNED, M.DONE)

    def _pending_mounts(self):
        """(task, station, cost) of each pending ring mount at a known station whose ring
        costs bases."""
        for t in self.kb.open_tasks():
            if t.kind != M.MOUNT_RING or t.state != M.PENDING:
                continue
            st = self.kb.stations.get(t.machine or "")
            cost = int(t.params.get("cost", 0))
            if st is not None and cost > 0:
                yield t, st, cost

    def waive_full_slide_puts(self) -> list[M.Task]:
        """Drop from each pending ring mount whose slide holds what its ring costs the
        pending puts of its bases that the slide has no room for (the puts stay, and
        go once the mount made room); returns the mounts changed."""
        changed = []
        for t, st, cost in self._pending_mounts():
            if st.loaded_with < cost:
                continue
            waived = [d for d in t.deps if self._blocked_put(self.kb.tasks.get(d), t.machine)]
            if not waived:
                continue
            deps: list[int] = []
            for d in t.deps:            # a waived put's own deps stay: what came before it
                for e in (self.kb.tasks[d].deps if d in waived else (d,)):   # (a cap retrieved)
                    if e not in deps:
                        deps.append(e)
            t.deps = tuple(deps)
            self.kb.save_task(t)
            changed.append(t)
            log.info("task %d: %s holds the %d base(s) it costs; it no longer waits for "
                     "task(s) %s, which the full slide cannot take", t.id, t.machine, cost,
                     waived)
        return changed

    def waive_stocked_puts(self) -> list[M.Task]:
        """Drop from each pending ring mount whose workpiece is ready, and that waits
        for nothing but its own bases (their puts on its slide, or the pickups that a
        waived put left it waiting for), while its slide holds what its ring costs
        beyond the bases other mounts waiting there have put, those steps (the bases go
        on the slide after it); the cap-less base's pickup (so the cap retrieval) goes
        to the product's cap mount, which must find the cap in its station.  The mount
        used to wait for its own bases beside bases other products had discarded on the
        slide (rcll2016 seed 9: a C2's robot held it at C-RS2 for 200 s beside 2 and 3
        bases while its cap-less base waited for its cap retrieval).  Returns the mounts
        changed."""
        changed = []
        for t, _st, cost in self._pending_mounts():
            deps = [self.kb.tasks.get(d) for d in t.deps]
            waiting = [d for d in deps if d is None or d.state != M.DONE]
            if not waiting or not all(self.own_base(d, t) for d in waiting):
                continue
            if not self.stocked_for(t):
                continue
            waived = {d.id for d in waiting}
            t.deps = tuple(d for d in t.deps if d not in waived)
            self.kb.save_task(t)
            capless = [q for d in waiting for q in [d] + [self.kb.tasks.get(e) for e in d.deps]
                       if q is not None and q.state != M.DONE and q.kind == M.GET_WORKPIECE
                       and q.params.get("role") == CAPLESS]
            product = self.kb.products.get(t.product or "")
            for cap in self.kb.tasks_of(product.tasks if product else ()):
                if cap.kind == M.MOUNT_CAP and cap.state == M.PENDING and capless:
                    cap.deps = tuple(cap.deps) + tuple(q.id for q in capless if q.id not in cap.deps)
                    self.kb.save_task(cap)
            changed.append(t)
            log.info("task %d: %s holds the %d base(s) it costs; it no longer waits for "
                     "its own, task(s) %s", t.id, t.machine, cost, sorted(waived))
        return changed

    def own_base(self, task: M.Task | None, mount: M.Task) -> bool:
        """Is ``task`` (a step ``mount`` waits for) a base for ``mount``'s slide: a put
        there, or the pickup of a base a put there carries on?"""
        if task is None or task.id == mount.params.get("carry_from"):
            return False
        if task.kind == M.PUT_WORKPIECE:
            return task.params.get("side") == M.SLIDE and task.machine == mount.machine
        return task.kind == M.GET_WORKPIECE and any(
            q.params.get("carry_from") == task.id and q.kind == M.PUT_WORKPIECE
            and q.params.get("side") == M.SLIDE and q.machine == mount.machine
            for q in self.kb.open_tasks())

    def stocked_for(self, mount: M.Task) -> bool:
        """Does ``mount``'s slide hold what its ring costs beyond the bases other pending
        mounts there have put (so that it need not wait for its own bases)?"""
        st, cost = self.kb.stations.get(mount.machine or ""), int(mount.params.get("cost", 0))
        return st is not None and cost > 0 and st.loaded_with - self._put_for_others(mount) >= cost

    def _put_for_others(self, mount: M.Task) -> int:
        """Bases on ``mount``'s slide that other pending mounts there have put."""
        n = 0
        for t in self.kb.open_tasks():
            if (t.kind != M.MOUNT_RING or t.state != M.PENDING or t.id == mount.id
                    or t.machine != mount.machine):
                continue
            done = sum(1 for d in t.deps if (q := self.kb.tasks.get(d)) is not None
                       and q.kind == M.PUT_WORKPIECE and q.state == M.DONE)
            n += min(done, int(t.params.get("cost", 0)))
        return n

    def _blocked_put(self, task: M.Task | None, machine: str) -> bool:
        return (task is not None and task.kind == M.PUT_WORKPIECE and task.state == M.PENDING
                and task.params.get("side") == M.SLIDE and task.machine == machine
                and self.room(machine, task.id) <= 0)

    def discard_to(self, task: M.Task, near, distance) -> None:
        """Send a discard that names no station to the nearest of our ring stations'
        slides with room (``distance(near, machine)``): there the base counts as an
        additional base (+2) where dropping it on the floor is a referee's call (2025:
        -10).  Left as it is (dropped where the robot stands) when no slide has room."""
        if task.kind != M.DISCARD or task.params.get("machine"):
            return
        best = self._nearest_slide(near, distance)
        if best is None:
            return
        task.params = {**task.params, "machine": best, "side": M.SLIDE}
        self.kb.save_task(task)
        log.info("task %d discards at %s's slide", task.id, best)

    def divert(self, task: M.Task, near, distance) -> bool:
        """A base waiting to go on a full slide goes to the nearest other slide of ours
        with room instead (a discard there, :meth:`discard_to`); a mount left short
        gets its bases fetched again (:meth:`top_up_slides`).  For when every robot
        holds what it cannot use yet (rcll2025 seed 18: from 480 s one held a base
        for C-RS1's full slide, two held products waiting for cap retrievals nobody
        was free to make).  True if diverted."""
        if (task.kind != M.PUT_WORKPIECE or task.params.get("side") != M.SLIDE
                or task.state != M.PENDING or self.room(task.machine, task.id) > 0):
            return False
        full, best = task.machine, self._nearest_slide(near, distance)   # (not the full one)
        if best is None:
            return False                # no other slide has room: it waits
        task.kind, task.params = M.DISCARD, {**task.params, "machine": best, "side": M.SLIDE}
        self.kb.save_task(task)
        log.info("task %d: %s's slide is full and every robot is stuck: its base goes to "
                 "%s's", task.id, full, task.params["machine"])
        return True

    def _nearest_slide(self, near, distance) -> str | None:
        """The nearest (``distance(near, machine)``) of our usable ring stations whose
        slide has room, or None: not one a wall leaves no room in front of
        (:mod:`.reach`), nor one the robots keep failing at (:mod:`.health`)."""
        paused = (self.health.unusable(self.clock.now())
                  if self.health is not None and self.clock is not None else frozenset())
        slides = [st.name for st in self.kb.stations.values()
                  if st.name.startswith(f"{self.prefix}-RS")
                  and st.state not in ("BROKEN", "DOWN") and self.room(st.name) > 0
                  and not self.reach.slide_walled(st.name) and f"{st.name}:{M.SLIDE}" not in paused]
        return min(slides, key=lambda m: distance(near, m)) if slides else None

    def top_up_slides(self) -> list[M.Task]:
        """Fetch the bases missing on the slide of each ring mount waiting only for
        them; returns the new slide puts."""
        if self.clock is None:
            return []
        now = self.clock.now()
        out = []
        for p in self.products.active():
            tasks = {t.id: t for t in self.kb.tasks_of(p.tasks)}
            for t in tasks.values():
                if t.kind != M.MOUNT_RING or t.state != M.PENDING or self.slide_ready(t):
                    continue
                deps = [tasks.get(d) or self.kb.tasks.get(d) for d in t.deps]
                if any(d is None or d.state != M.DONE for d in deps):
                    continue                # its own bases may still be coming
                last = max([d.finished_at or 0.0 for d in deps
                            if d.kind == M.PUT_WORKPIECE] + [0.0])
                if now - last < self.settle:
                    continue                # the refbox may not have counted the last one
                st = self.kb.stations.get(t.machine)
                coming = sum(1 for q in tasks.values() if q.id not in t.deps
                             and q.kind == M.PUT_WORKPIECE and q.state in M.OPEN_STATES
                             and q.machine == t.machine and q.params.get("side") == M.SLIDE
                             and self._under_way(q))
                missing = int(t.params.get("cost", 0)) - (st.loaded_with if st else 0) - coming
                if missing > 0:             # (bases the mount no longer waits for still come)
                    out += self._top_up(p, t, missing)
        return out

    def _under_way(self, put: M.Task) -> bool:
        """Is the base of ``put`` (a put on a slide) under way: the put sent, or its
        base held or being fetched, or the steps that free it (a cap-less base's cap
        retrieval) started?  A put whose base nobody has started on does not count as
        coming: the mount's robot would hold its product until then (rcll2016 seed 2,
        rendered: two robots held products 372 s and 414 s at C-RS2 for one base each,
        their own cap-less bases, whose cap retrievals at C-CS2 had not begun)."""
        if put.state == M.ASSIGNED:
            return True
        todo, seen = [put.params.get("carry_from"), *put.deps], set()
        while todo:
            tid = todo.pop()
            src = self.kb.tasks.get(tid) if tid is not None and tid not in seen else None
            if src is None:
                continue
            seen.add(tid)
            if src.state in (M.ASSIGNED, M.DONE):
                return True
            todo.extend(src.deps)
        return False

    def _top_up(self, product: M.Product, mount: M.Task, n: int) -> list[M.Task]:
        bs = f"{self.prefix}-BS"
        order = self.kb.orders.get(product.order_id)
        base = order.base if order is not None else "BASE_RED"
        made, created = [], self.kb.get("game_time", 0.0)
        for _ in range(n):
            get = M.Task(self.kb.next_id("task"), M.GET_WORKPIECE,
                         {"machine": bs, "side": M.OUTPUT, "base": base, "role": EXTRA},
                         product=product.id, prepare={"machine": bs, "bs": {
                             "side": M.OUTPUT, "color": base}},
                         locks=(bs,), releases=(bs,), created=created)
            put = M.Task(self.kb.next_id("task"), M.PUT_WORKPIECE,
                         {"machine": mount.machine, "side": M.SLIDE, "carry_from": get.id},
                         product=product.id, deps=(get.id,), carry=True, created=created)
            self.kb.save_task(get)
            self.kb.save_task(put)
            mount.deps = tuple(mount.deps) + (put.id,)
            product.tasks = tuple(product.tasks) + (get.id, put.id)
            made.append(put)
        self.kb.save_task(mount)
        self.kb.save_product(product)
        log.info("%s: %s lacks %d base(s) for task %d: fetching them", product.id,
                 mount.machine, n, mount.id)
        return made
