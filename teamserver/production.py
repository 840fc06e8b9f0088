"""Products: from chosen orders to tasks, bookkeeping of their progress, repair.

A :class:`~teamserver.knowledge.model.Product` owns the tasks of one unit of an
order.  When a task finishes, the workpieces it moved are updated (where
each is, which rings and cap it has), the station locks its product gives
up are released, and carry steps are bound to the robot that now holds the
workpiece.  A product that cannot go on as planned (a failed step, a
station that broke with its workpiece inside, a robot lost with it) is
*repaired*: its open tasks are cancelled and the rest of the product is
planned again from what exists (the workpiece as it is, bases already on a
slide, a cap already buffered); if nothing can be made of it, it is
abandoned and a station output it blocks is cleared.  With a storage station
a finished product may wait there for its window (:mod:`.storage`).
"""
from __future__ import annotations

import logging

from rll_bt.rules import Profile

from .caps import CLEANUP_ORDER, FREE, CapsMixin
from .cleanup import CleanupMixin
from .health import StationHealth
from .knowledge import model as M
from .knowledge.kb import KnowledgeBase
from .planning.domain import CAP_LOCK, CAPLESS, EXTRA, MAIN, Progress
from .planning.estimate import SimRobot, SimTask
from .planning.htn import Network, PlanningFailed
from .planning.planner import Candidate, ProductionPlanner, World
from .slides import SlidesMixin
from .storage import StorageMixin

log = logging.getLogger("teamserver.production")

DELIVERED, ABANDONED, ACTIVE = "DELIVERED", "ABANDONED", "ACTIVE"


class ProductionManager(CapsMixin, CleanupMixin, SlidesMixin, StorageMixin):
    """Products, their tasks and workpieces, kept in the knowledge base."""

    def __init__(self, kb: KnowledgeBase, planner: ProductionPlanner, prefix: str, *,
                 cs_caps: dict[str, str], max_products: int | None = None,
                 max_repairs: int = 3, clock=None, confirm_time: float = 20.0,
                 prefill: bool = True):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.planner = planner
        self.prefix = prefix
        self.cs_caps = {f"{prefix}-{k}" if not k.startswith(prefix + "-") else k: v
                        for k, v in cs_caps.items()}
        self.max_products = max_products
        self.max_repairs = max_repairs
        self.clock = clock
        self._positions: tuple | None = None     # (what they were computed from, positions)
        self.health = StationHealth(kb)
        self.confirm_time = confirm_time
        self.prefill_caps = prefill
        self.prefill_stop = 120.0       # no caps retrieved ahead this close to the end (s)
        self.prefill_unknown = 600.0    # until then a cap colour no order wants yet may come

    def unusable(self) -> frozenset[str]:
        """Places the robots keep failing at (see :mod:`teamserver.health`)."""
        return self.health.unusable(self.clock.now()) if self.clock is not None else frozenset()

    # -- locks and buffers (persisted in the knowledge base) ------------------------
    @property
    def locks(self) -> dict[str, str]:
        return dict(self.kb.get("locks", {}))

    def _set_locks(self, locks: dict[str, str]) -> None:
        self.kb.set("locks", locks)

    def lock_free(self, task: M.Task) -> bool:
        """Its product may take the task's locks, and no other running task uses them
        (a station serves one robot at a time, even within one product)."""
        if not task.locks:
            return True
        locks = self.locks
        if any(locks.get(lk, task.product) != task.product for lk in task.locks):
            return False
        mine = set(task.locks)
        return not any(t.id != task.id and t.state == M.ASSIGNED and mine & set(t.locks)
                       for t in self.kb.open_tasks())

    def acquire(self, task: M.Task) -> None:
        if task.locks:
            locks = self.locks
            locks.update(dict.fromkeys(task.locks, task.product))
            self._set_locks(locks)

    def release(self, product: str, names=None) -> None:
        locks = self.locks
        for lk in list(locks):
            if locks[lk] == product and (names is None or lk in names):
                del locks[lk]
        self._set_locks(locks)

    # -- the planning world -------------------------------------------------------------
    def rs_colors(self) -> dict[str, tuple[str, ...]]:
        out = {}
        for kind in self.profile.machine_types:
            if not kind.startswith("RS"):
                continue
            name = f"{self.prefix}-{kind}"
            st = self.kb.stations.get(name)
            if st is not None and st.ring_colors:
                out[name] = tuple(st.ring_colors)
            elif self.profile.rs_colors is not None:
                out[name] = tuple(self.profile.rs_colors[kind])
        return out

    def positions(self) -> dict[str, tuple[float, float]]:
        """Our machines' best known positions (recomputed when observations or station
        records changed)."""
        key = (self.kb.observation_count, tuple((n, s.zone) for n, s in
                                                sorted(self.kb.stations.items())))
        if self._positions is not None and self._positions[0] == key:
            return dict(self._positions[1])
        out = {}
        for kind in self.profile.machine_types:
            name = f"{self.prefix}-{kind}"
            pos = self.kb.machine_position(name)
            if pos is not None:
                out[name] = pos
        self._positions = (key, out)
        return dict(out)

    def active_products(self) -> list[M.Product]:
        return [p for p in self.kb.products.values() if p.state == ACTIVE]

    def unconfirmed(self, game_time: float) -> dict[int, int]:
        """Order id -> our deliveries the refbox has not counted yet, of those made less
        than ``confirm_time`` game seconds ago.  An older one it never counted did not
        reach it (the workpiece was lost, or judged for no order): its unit is open again."""
        delivered: dict[int, int] = {}
        recent: dict[int, int] = {}
        for p in self.kb.products.values():
            if p.state == DELIVERED and p.order_id != CLEANUP_ORDER:
                delivered[p.order_id] = delivered.get(p.order_id, 0) + 1
                if p.delivered_at is None or game_time - p.delivered_at <= self.confirm_time:
                    recent[p.order_id] = recent.get(p.order_id, 0) + 1
        out = {}
        for oid, n in recent.items():
            o = self.kb.orders.get(oid)
            if o is not None and delivered[oid] > o.delivered:
                out[oid] = min(n, delivered[oid] - o.delivered)
        return out

    def world(self, game_time: float, horizon: float, exclude: str | None = None) -> World:
        """The planning world now (``exclude``: a product whose tasks are left out, the
        one being planned again)."""
        orders = [o for o in self.kb.orders.values() if o.open > 0]
        in_progress = self.unconfirmed(game_time)
        making = 0
        active, done = [], set()
        for p in self.active_products():
            in_progress[p.order_id] = in_progress.get(p.order_id, 0) + 1
            making += p.order_id != CLEANUP_ORDER
            if p.id == exclude:
                continue
            order = self.kb.orders.get(p.order_id)
            for t in self.kb.tasks_of(p.tasks):
                if t.state == M.CANCELLED or t.state == M.FAILED:
                    continue
                if t.state == M.DONE:
                    done.add(t.id)
                holder = t.holder if t.holder is not None else (
                    t.robot if t.state == M.ASSIGNED else None)
                active.append(SimTask(
                    key=t.id, product=p.id, kind=t.kind, machine=t.machine, params=t.params,
                    deps=t.deps, locks=t.locks, releases=t.releases, carry=t.carry,
                    holder=None if holder is None else str(holder),
                    not_before=float(t.params.get("not_before", 0.0)), order=order))
        robots = []
        for r in self.kb.active_robots():
            pos = (r.pose[0], r.pose[1]) if r.pose else self._start_position()
            robots.append(SimRobot(str(r.number), pos, game_time))
        n = self.max_products if self.max_products is not None else max(len(robots), 1)
        unusable = self.unusable()
        if self.planner.ss is not None and not self.storage_open():
            unusable |= {self.planner.ss}
        return World(orders, robots, self.positions(), self.rs_colors(),
                     dict(self.kb.get("ring_costs") or {}), self.cs_caps, game_time, horizon,
                     active=active, done=done, owned=self.locks, in_progress=in_progress,
                     unusable=unusable, max_products=n, making=making)

    def _start_position(self) -> tuple[float, float]:
        from rll_bt.rules import CYAN, MAGENTA
        team = CYAN if self.prefix == "C" else MAGENTA
        rect = self.profile.insertion.get(team)
        return rect.centre if rect else (0.0, 0.0)

    def ready_to_plan(self) -> bool:
        """Ring costs and RS colours are known (needed by every ring method)."""
        return bool(self.kb.get("ring_costs")) and bool(self.rs_colors())

    # -- starting products ------------------------------------------------------------
    def plan(self, game_time: float, horizon: float):
        """Repair what needs it, then start the orders the planner picks.
        Returns (tasks to cancel, the planner's Choice or None)."""
        cancels: list[M.Task] = []
        for p in self.active_products():
            if p.repair:
                cancels += self.repair(p)
            else:
                self.redecide(p)
        if not self.ready_to_plan():
            return cancels, None
        self.adopt_free_caps()
        choice = self.planner.choose(self.world(game_time, horizon))
        for cand in choice.start:
            self.start(cand)
        if self.prefill_caps and self.spare_robots() > 0:
            self.prefill(game_time, horizon)
        return cancels, choice

    def start(self, cand: Candidate) -> M.Product:
        pid = f"P{self.kb.next_id('product')}"
        product = M.Product(pid, cand.order.id, created=self.kb.get("game_time", 0.0))
        net = cand.network
        self.kb.save_product(product)
        self.add_network(product, net)
        log.info("started %s for order %d (%d tasks)", pid, cand.order.id,
                 len(cand.network.steps))
        return product

    def add_network(self, product: M.Product, net: Network) -> list[M.Task]:
        ids = [self.kb.next_id("task") for _ in net.steps]
        tasks = []
        for i, st in enumerate(net.steps):
            f = st.fields
            deps = tuple(ids[j] for j in net.predecessors(i))
            params = dict(f["params"])
            if f["carry"]:
                pick = [ids[j] for j in net.predecessors(i)
                        if net.steps[j].fields["kind"] == M.GET_WORKPIECE]
                if pick:
                    params["carry_from"] = pick[0]
            holder = int(f["holder"]) if f["holder"] is not None else None
            t = M.Task(ids[i], f["kind"], params, product=product.id, deps=deps,
                       prepare=f["prepare"], locks=f["locks"], releases=f["releases"],
                       carry=f["carry"], holder=holder, created=self.kb.get("game_time", 0.0))
            self.kb.save_task(t)
            tasks.append(t)
        product.tasks = tuple(product.tasks) + tuple(ids)
        self.kb.save_product(product)
        self.fill_places(product, tasks)
        return tasks

    # -- progress ---------------------------------------------------------------------
    def progress(self, product: M.Product) -> Progress:
        pr = Progress()
        wp = self.kb.workpieces.get(product.workpiece) if product.workpiece else None
        if wp is not None and self._workpiece_exists(wp):
            pr.base, pr.rings, pr.cap, pr.location = wp.base, tuple(wp.rings), wp.cap, wp.location
        credit: dict[str, int] = {}
        for t in self.kb.tasks_of(product.tasks):
            if t.state != M.DONE:
                continue
            if t.kind == M.PUT_WORKPIECE and t.params.get("side") == M.SLIDE:
                credit[t.machine] = credit.get(t.machine, 0) + 1
            elif t.kind == M.MOUNT_RING:
                credit[t.machine] = credit.get(t.machine, 0) - int(t.params.get("cost", 0))
        pr.slide_credit = {k: v for k, v in credit.items() if v > 0}
        for cs, owner in self.cap_buffer.items():
            if owner == product.id:
                pr.cap_ready = cs
        if pr.location is not None and pr.location.endswith(":" + M.SHELF):
            pr.stored_at = self.place_of(product.id)
            if self.brought_out(product):
                pr.location = f"{self.planner.ss}:{M.OUTPUT}"
        return pr

    def _workpiece_exists(self, wp: M.Workpiece) -> bool:
        loc = wp.location
        if loc == "gone":
            return False
        if loc.startswith("robot:"):
            r = self.kb.robots.get(int(loc[6:]))
            return r is not None and r.status == M.ACTIVE
        if loc.endswith(":" + M.SHELF):
            return True                 # a broken storage station keeps its shelf
        st = self.kb.stations.get(loc.split(":")[0])
        return st is None or st.state not in ("BROKEN",)

    # -- task outcomes ----------------------------------------------------------------
    def task_done(self, task: M.Task, robot: M.Robot) -> None:
        """Book the effects of a finished task on workpieces, locks and buffers."""
        product = self.kb.products.get(task.product) if task.product else None
        kind, machine = task.kind, task.machine
        if kind == M.GET_WORKPIECE:
            role = task.params.get("role", MAIN)
            wp = self._workpiece_for_pickup(task, product, role)
            wp.location = f"robot:{robot.number}"
            self.kb.save_workpiece(wp)
            robot.holding = wp.id
            for other in self.kb.tasks_of(product.tasks if product else ()):
                if other.params.get("carry_from") == task.id and other.state == M.PENDING:
                    other.holder = robot.number
                    self.kb.save_task(other)
            if machine == self.planner.ss and product is not None:
                self.free_place(product.id)     # retrieved
            elif product is not None and wp.cap is not None and role == MAIN:
                self.redecide(product)          # finished: store it after all, or not
        elif kind == M.RETRIEVE_CAP:
            wp = M.Workpiece(f"{task.product}/capless{task.id}", base="?", cap=None,
                             location=f"{machine}:{M.OUTPUT}", product=task.product)
            self.kb.save_workpiece(wp)
            ahead = product is not None and product.order_id == CLEANUP_ORDER
            self._take_cap(machine, FREE if ahead else task.product)
        elif kind in (M.MOUNT_RING, M.MOUNT_CAP):
            wp = self.kb.workpieces.get(robot.holding or "")
            if wp is not None:
                if kind == M.MOUNT_RING:
                    wp.rings = tuple(wp.rings) + (task.params["ring_color"],)
                else:
                    wp.cap = task.params.get("cap_color")
                    buf = self.cap_buffer
                    buf.pop(machine, None)
                    self._set_cap_buffer(buf)
                wp.location = f"{machine}:{M.OUTPUT}"
                self.kb.save_workpiece(wp)
            robot.holding = None
        elif kind == M.PUT_WORKPIECE and task.params.get("store"):
            self.stored(task, self.kb.workpieces.get(
                (product.workpiece if product is not None else None) or robot.holding or ""))
            robot.holding = None
        elif kind in (M.PUT_WORKPIECE, M.DELIVER, M.DISCARD):
            wp = self.kb.workpieces.get(robot.holding or "")
            if wp is not None:
                wp.location = "gone"
                self.kb.save_workpiece(wp)
            robot.holding = None
            if kind == M.DELIVER and product is not None:
                product.state = DELIVERED
                product.delivered_at = float(self.kb.get("game_time", 0.0))
                self.kb.save_product(product)
                self.release(product.id)
        if task.releases and product is not None:
            self.release(product.id, set(task.releases))
        if (product is not None and product.state == ACTIVE and product.order_id == CLEANUP_ORDER
                and all(t.state in M.CLOSED_STATES for t in self.kb.tasks_of(product.tasks))):
            product.state = DELIVERED
            self.kb.save_product(product)
            self.release(product.id)

    def _workpiece_for_pickup(self, task: M.Task, product: M.Product | None,
                              role: str) -> M.Workpiece:
        machine = task.machine
        here = f"{machine}:{M.OUTPUT}"
        if product is not None and role == MAIN:
            if machine.endswith("BS"):
                wp = M.Workpiece(f"{product.id}/wp{task.id}", base=task.params.get("base"),
                                 product=product.id)
            else:
                wp = self.kb.workpieces.get(product.workpiece or "") or M.Workpiece(
                    f"{product.id}/wp{task.id}", product=product.id)
            product.workpiece = wp.id
            self.kb.save_product(product)
            return wp
        if role == CAPLESS:
            for wp in self.kb.workpieces.values():
                if wp.location == here and wp.id.startswith(f"{task.product}/capless"):
                    return wp
        base = task.params.get("base") if machine.endswith("BS") else "?"
        return M.Workpiece(f"{task.product}/{EXTRA}{task.id}", base=base, product=task.product)

    def retry(self, task: M.Task) -> M.Task:
        """A fresh copy of a failed step under a new id (agents remember the outcome
        of a task id, so a retry must not reuse it); dependants follow the copy."""
        new = M.Task.from_dict({**task.to_dict(), "id": self.kb.next_id("task"),
                                "state": M.PENDING, "robot": None, "assigned_at": None,
                                "prepared_at": None, "finished_at": None})
        self.kb.save_task(new)
        task.state = M.FAILED
        self.kb.save_task(task)
        product = self.kb.products.get(task.product or "")
        if product is not None:
            product.tasks = tuple(product.tasks) + (new.id,)
            self.kb.save_product(product)
            for t in self.kb.tasks_of(product.tasks):
                changed = False
                if task.id in t.deps:
                    t.deps = tuple(new.id if d == task.id else d for d in t.deps)
                    changed = True
                if t.params.get("carry_from") == task.id:
                    t.params["carry_from"] = new.id
                    changed = True
                if changed:
                    self.kb.save_task(t)
        return new

    def needs_repair(self, product_id: str | None, why: str) -> None:
        p = self.kb.products.get(product_id or "")
        if p is not None and p.state == ACTIVE and not p.repair:
            p.repair = why
            self.kb.save_product(p)
            log.info("%s needs repair: %s", p.id, why)

    def station_broke(self, machine: str) -> None:
        """A BROKEN station loses what it holds: workpieces inside, a buffered cap (but
        not the storage station's shelf)."""
        for wp in self.kb.workpieces.values():
            if wp.location.startswith(machine + ":") and not wp.location.endswith(M.SHELF):
                wp.location = "gone"
                self.kb.save_workpiece(wp)
                self.needs_repair(wp.product, f"{machine} broke with its workpiece")
        buf = self.cap_buffer
        owner = buf.pop(machine, None)
        if owner is not None:
            self._set_cap_buffer(buf)
            self.needs_repair(owner, f"{machine} broke and lost the buffered cap")
        for t in self.kb.open_tasks():
            if t.machine == machine and t.prepared_at is not None and t.state == M.ASSIGNED:
                t.prepared_at = None            # to be prepared again once it is IDLE
                self.kb.save_task(t)

    # -- repair ---------------------------------------------------------------------------
    def repair(self, product: M.Product) -> list[M.Task]:
        """Cancel the product's open tasks and plan the rest again; returns the
        tasks that were assigned (the robots must be told to stop)."""
        cancels = self.restart(product)
        product.repair, product.repairs = None, product.repairs + 1
        order = self.kb.orders.get(product.order_id)
        net = None
        if order is not None and order.open > 0 and product.repairs <= self.max_repairs:
            try:
                net = self.plan_rest(product, order)
            except PlanningFailed as exc:
                log.info("%s cannot be repaired: %s", product.id, exc)
        if net is None:
            self.abandon(product)
        else:
            self.add_network(product, net)
            self.kb.save_product(product)
        return cancels

    def restart(self, product: M.Product) -> list[M.Task]:
        """Cancel the product's open tasks and keep only the locks of what exists of it
        (a buffered cap, the station output its workpiece is on); returns the tasks
        that were assigned."""
        cancels = self.cancel_open(product)
        pr = self.progress(product)
        self.release(product.id)
        owned = {}
        if pr.cap_ready:
            owned[pr.cap_ready + CAP_LOCK] = product.id
        if pr.location and pr.location.endswith(":" + M.OUTPUT):
            owned[pr.location.split(":")[0]] = product.id
        if owned:
            locks = self.locks
            locks.update(owned)
            self._set_locks(locks)
        return cancels

    def cancel_open(self, product: M.Product) -> list[M.Task]:
        cancels = []
        for t in self.kb.tasks_of(product.tasks):
            if t.state in M.OPEN_STATES:
                if t.state == M.ASSIGNED:
                    cancels.append(M.Task.from_dict(t.to_dict()))
                    r = self.kb.robots.get(t.robot)
                    if r is not None and r.task_id == t.id:
                        r.task_id = None
                        self.kb.save_robot(r)
                t.state = M.CANCELLED
                self.kb.save_task(t)
        return cancels

    def abandon(self, product: M.Product, pr: Progress | None = None) -> None:
        pr = pr or self.progress(product)
        product.state = ABANDONED
        self.kb.save_product(product)
        self.release(product.id)
        buf = self.cap_buffer
        for cs in [cs for cs, owner in buf.items() if owner == product.id]:
            buf[cs] = FREE              # a retrieved cap another product can mount
        self._set_cap_buffer(buf)
        if pr.location and pr.location.endswith(":" + M.SHELF):
            pass                        # it stays on the shelf; so does its reservation
        elif pr.location and not pr.location.startswith("robot:"):
            self.clear_output(pr.location.split(":")[0])
            self.free_place(product.id)
        else:
            self.free_place(product.id)
        log.info("abandoned %s", product.id)

    def feed_lost(self, task: M.Task) -> None:
        """``task`` was reported done, but its station never took the workpiece: undo
        what :meth:`task_done` booked and repair the product."""
        task.state, task.error = M.FAILED, "the station never took the workpiece"
        self.kb.save_task(task)
        machine = task.machine
        for wp in self.kb.workpieces.values():
            if wp.product == task.product and wp.location.startswith(machine + ":"):
                wp.location = "gone"
                self.kb.save_workpiece(wp)
        product = self.kb.products.get(task.product or "")
        buf = self.cap_buffer
        if task.kind == M.MOUNT_CAP and product is not None:
            buf[machine] = product.id               # the cap is still in the station
        elif task.kind == M.RETRIEVE_CAP:
            # the carrier never got there: the cap :meth:`task_done` booked in the
            # station is not there either, whoever has claimed it since
            owner = buf.pop(machine, None)
            if owner not in (None, FREE, task.product):
                self.needs_repair(owner, f"{machine} never got the cap it was to mount")
        self._set_cap_buffer(buf)
        if product is None:
            return
        if product.state == DELIVERED:
            product.state, product.delivered_at = ACTIVE, None
            self.kb.save_product(product)
        # a clean-up product has no order: its repair cancels what is left of it and
        # frees its locks (its tasks would wait for a station output that never comes)
        self.needs_repair(product.id, f"{machine} never took the workpiece of task {task.id}")
