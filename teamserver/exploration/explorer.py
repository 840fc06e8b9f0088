"""Exploration as the team server runs it, tick by tick.

While exploring (2016: the EXPLORATION phase; 2017+: the first part of
PRODUCTION until every own station is reported), :class:`Explorer` gives
idle robots zones to explore (the chosen strategy, :mod:`.strategies`),
turns robots away from zones chosen blindly once an observation gives
their strategy a better one, and reports what is due to the refbox every
``report_period`` seconds (:mod:`.report`).  2017+, once every zone is
reported it keeps reporting through the exploration window and sends one
robot at a time to look at a station whose rotation is lacking
(:mod:`.lookout`).  When exploration ends its tasks are cancelled.

2017+, production goes on beside exploration's tail (:meth:`Explorer.beside`):
once our base, delivery and a cap station are reported, exploration keeps
at most one robot per own station still unfound (:meth:`Explorer.unfound`)
and the others produce, with work only for products whose stations are all
found (the dispatcher's readiness asks :meth:`Explorer.unfound`).  On a
lossy link exploration's last station comes late (2025 seed 1 at 20 % loss,
2 s delay: the storage station 45 s after the six others) while the robots
could already make what needs none of it.
"""
from __future__ import annotations

from collections.abc import Callable

from rll_bt.rules import Profile

from ..dispatch.fleet import Fleet
from ..knowledge import model as M
from ..knowledge.kb import KnowledgeBase
from ..links.refbox import RefboxClient
from ..links.tasks import TaskLink
from .lookout import LOOK, Lookout, is_look
from .report import Reporter
from .strategies import Strategy
from .symmetry import consistent_set
from .view import ExplorationView


class Explorer:
    """See the module doc.  ``to_refbox(msg)`` sends on our team channel;
    ``on_end()`` is called when exploration tasks are cancelled because
    exploration is over."""

    def __init__(self, kb: KnowledgeBase, clock, strategy: Strategy, reporter: Reporter,
                 lookout: Lookout, refbox: RefboxClient, fleet: Fleet, tasks: TaskLink,
                 to_refbox: Callable[[object], None], *, report_period: float = 1.0,
                 on_end: Callable[[], None] = lambda: None):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.clock = clock
        self.strategy = strategy
        self.reporter = reporter
        self.lookout = lookout
        self.refbox = refbox
        self.fleet = fleet
        self.tasks = tasks
        self.to_refbox = to_refbox
        self.report_period = report_period
        self.on_end = on_end
        self._last_report = -1e9
        self._last_redirect = None          # the observation count last looked at

    @property
    def color(self) -> str | None:
        return self.kb.get("team_color")

    def active(self) -> bool:
        """Is it exploration time for us (see the module doc)?"""
        if not self.refbox.exploring():
            return False
        if self.refbox.phase == "EXPLORATION":
            return True
        # exploring inside PRODUCTION (2017+): until everything is reported
        own = self.profile.machines(self.color)
        reported = self.kb.reported
        return not all(m in reported and "zone" in reported[m] for m in own)

    def unfound(self) -> frozenset[str]:
        """Our stations whose zone is not reported yet while we explore (none once
        exploration is over)."""
        if not self.active():
            return frozenset()
        reported = self.kb.reported
        return frozenset(m for m in self.profile.machines(self.color)
                         if "zone" not in reported.get(m, {}))

    def beside(self) -> bool:
        """May production go on beside exploration now (2017+, inside PRODUCTION,
        our base, delivery and a cap station reported)?"""
        if self.refbox.phase != "PRODUCTION" or self.color is None:
            return False
        gone = self.unfound()
        own = [m for m in self.profile.machines(self.color) if m not in gone]
        kinds = {m.split("-", 1)[1] for m in own}
        return "BS" in kinds and "DS" in kinds and any(k.startswith("CS") for k in kinds)

    def zones(self) -> list[int]:
        """The zones to explore (the refbox's, else those our machines may be in)."""
        zones = self.kb.get("exploration_zones")
        if zones:
            return [int(z) for z in zones]
        return self.profile.machine_zones(self.color)

    def explore(self) -> None:
        """One exploration step: zones for idle robots, redirects, reports."""
        busy = {int(t.params["zone"]) for t in self.kb.open_tasks()
                if t.kind == M.EXPLORE_ZONE and t.state == M.ASSIGNED}
        self._redirect_blind(busy)
        robots = self.fleet.idle_robots()
        if self.beside():           # one explorer per station unfound, the rest produce
            exploring = sum(1 for t in self.kb.open_tasks()
                            if t.kind == M.EXPLORE_ZONE and t.state == M.ASSIGNED and not is_look(t))
            room = len(self.unfound()) - exploring
            robots = [r for r in self.fleet.available_robots() if not r.holding][:max(room, 0)]
        for r in robots:
            view = ExplorationView.from_kb(self.kb, self.color, self.zones(), busy, lights=self.reporter.lights)
            d = self.strategy.next_zone(view, r.pose)
            if d is None:
                continue
            t = self.fleet.assign_explore(r, d.zone)
            t.params["branch"] = d.branch
            self.kb.save_task(t)
            busy.add(d.zone)
        self._report_due()

    def _report_due(self) -> None:
        now = self.clock.now()
        if now - self._last_report >= self.report_period:
            self._last_report = now
            self.report()

    def _redirect_blind(self, busy: set[int]) -> None:
        """Turn robots away from zones their strategy chose blindly once it has
        a better one for them (``Strategy.redirect``); looked at whenever an
        observation came in.  The freed robots get their new zone at once."""
        blind = [t for t in self.kb.open_tasks() if t.kind == M.EXPLORE_ZONE
                 and t.state == M.ASSIGNED and not is_look(t)]
        if not blind or self._last_redirect == self.kb.observation_count:
            return
        self._last_redirect = self.kb.observation_count
        cs = consistent_set(self.profile, self.kb.machines)
        claimed: set[int] = set()
        for t in blind:
            zone = int(t.params["zone"])
            r = self.kb.robots.get(t.robot) if t.robot is not None else None
            view = ExplorationView.from_kb(self.kb, self.color, self.zones(),
                                           (busy | claimed) - {zone}, cs, lights=self.reporter.lights)
            d = self.strategy.redirect(view, t.params.get("branch"), r.pose if r else None)
            if d is not None:
                self.cancel(t, f"{self.profile.zone_name(d.zone)} was observed")
                busy.discard(zone)
                claimed.add(d.zone)

    def report(self) -> list[dict]:
        """Report what is due (see :mod:`teamserver.exploration.report`); returns the entries."""
        cs = consistent_set(self.profile, self.kb.machines)
        new = self.reporter.new_values(cs, self.kb.reported, self.refbox.exploration_left(),
                                       self.refbox.type_string)
        for name, vals in new.items():
            self.kb.mark_reported(name, vals)
        entries = self.reporter.entries(self.kb.reported)
        if entries and self.color is not None:
            self.to_refbox(self.refbox.machine_report(entries))
        return entries

    def end(self) -> None:
        """Exploration is over: cancel every exploration task."""
        for t in self.kb.open_tasks():
            if t.kind == M.EXPLORE_ZONE:
                self.cancel(t, "exploration is over")
        self.on_end()

    def exploring_blindly(self) -> bool:
        """Are exploration tasks other than looks open?"""
        return any(t.kind == M.EXPLORE_ZONE and not is_look(t) for t in self.kb.open_tasks())

    def cancel(self, t: M.Task, reason: str) -> None:
        """Cancel an exploration task (its robot is told if it has it)."""
        if t.state == M.ASSIGNED:
            self.tasks.cancel(t, reason)
        r = self.kb.robots.get(t.robot) if t.robot is not None else None
        if r is not None and r.task_id == t.id:
            r.task_id = None
            self.kb.save_robot(r)
        t.state = M.CANCELLED
        self.kb.save_task(t)

    def look_for_rotations(self) -> None:
        """2017+, in the exploration window after every zone is reported: keep
        reporting, and send a robot to look at a station whose rotation is
        still lacking (see :mod:`teamserver.exploration.lookout`)."""
        if not self.refbox.exploring():
            if any(is_look(t) for t in self.kb.open_tasks()):
                self.end()
            return
        self._report_due()
        cs = self.lookout.consistent(self.kb)
        for t in self.lookout.done_looks(self.kb, cs):
            self.cancel(t, f"the rotation of {t.params[LOOK]} is known")
        for target in self.lookout.targets(self.kb, cs, self.refbox.exploration_left()):
            r = self.lookout.pick_robot(self.fleet.available_robots(), target, self.kb)
            if r is None:
                break
            t = self.fleet.assign_explore(r, target.zone)
            t.params.update({LOOK: target.machine, "branch": "look",
                             "viewpoints": [list(v) for v in target.viewpoints]})
            self.kb.save_task(t)
