"""The team server core, stepped by :meth:`TeamServer.tick`.

    server = TeamServer("rcll2016", "Carologistics", key="randomkey", clock=clock,
                        refbox=RefboxLink(...), agents=stream_server, state="game.sqlite")
    while True:
        server.tick()          # reads both links, decides, sends; never blocks

One tick: take in everything the refbox and the robots sent; drop robots
whose heartbeat stopped; during exploration give idle robots zones to
explore (the chosen strategy) and report to the refbox; during production
repair and extend the plan when something changed (a new order, a failed
task, a station that broke or went down, a lost robot, or every
``replan_period`` seconds), give ready tasks to idle robots and send
PrepareMachine just before each robot arrives; then send GamePhase,
MachineMap and heartbeats to the robots.  All state goes through the
knowledge base into SQLite, so a new TeamServer on the same ``state`` file
carries on where a killed one stopped.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from rll_bt import rules
from rll_bt.clock import Clock
from rll_bt.comm.transport import CONNECTED, DISCONNECTED
from rll_bt.rules import CYAN, MAGENTA, PREFIX, Profile

from .dispatch import DispatchConfig, Dispatcher
from .exploration.lookout import LOOK, Lookout, is_look
from .exploration.report import Reporter
from .exploration.strategies import DEFAULT_THRESH, make_strategy
from .exploration.symmetry import consistent_set
from .exploration.view import ExplorationView
from .knowledge import model as M
from .knowledge.kb import KnowledgeBase
from .knowledge.store import Store
from .links.agents import AgentLink
from .links.refbox import RefboxClient
from .planning.estimate import Durations
from .planning.planner import StoragePolicy, make_planner
from .production import ProductionManager

log = logging.getLogger("teamserver")

BUSY = 2                   # RobotStatus.State.BUSY
#: cap colour on each cap station's shelf (the refbox's default set-up)
DEFAULT_CS_CAPS = {"CS1": "CAP_GREY", "CS2": "CAP_BLACK"}


@dataclass
class ServerConfig:
    """Tuning of the team server.  Times in seconds of its clock."""

    strategy: str = "algorithm1"
    planner: str = "htn"                        # production: "htn", or the "greedy" baseline
    seed: int = 0
    explore_thresh: float = DEFAULT_THRESH      # Algorithm 1's thresh, and report confidence
    report_margin: float = 20.0                 # report whatever pays this long before the end
    report_period: float = 1.0
    replan_period: float = 10.0
    plan_budget: float = 0.04                   # s of wall time per planning round
    plan_max_evaluations: int = 60
    max_products: int | None = None             # default: one per robot
    prefill_caps: bool = True                   # retrieve caps ahead into idle cap stations
    storage: StoragePolicy | None = None        # storing early products (None: the planner's)
    cs_caps: dict[str, str] = field(default_factory=lambda: dict(DEFAULT_CS_CAPS))
    durations: Durations = field(default_factory=Durations)
    dispatch: DispatchConfig = field(default_factory=DispatchConfig)
    phase_period: float = 1.0                   # GamePhase + heartbeats to the robots
    map_period: float = 1.0                     # at most this often a changed MachineMap
    beacon: bool = False                        # send a BeaconSignal of our own
    beacon_number: int = 0
    beacon_period: float = 1.0


class TeamServer:
    """The in-process team server.

    ``refbox``: a :class:`~teamserver.links.refbox_link.RefboxLink` (or anything with
    ``receive()``, ``send(msg)`` and ``set_team(color, key)``), None to run
    without a refbox.  ``agents``: a stream server transport of the team
    protocol (``receive()``, ``events()``, ``send(msg, to=peer)``).
    ``state``: SQLite file of the knowledge base (":memory:" for none).
    ``oracle``: machine -> true zone, only for ``strategy="oracle"``.
    ``team_color``: force our colour (a training game without team names).
    """

    def __init__(self, profile: str | Profile, team_name: str, *, clock: Clock, refbox=None,
                 agents=None, key: str | None = None, state: str | Path = ":memory:",
                 config: ServerConfig | None = None, oracle: dict[str, int] | None = None,
                 team_color: str | None = None):
        self.profile = rules.profile(profile) if isinstance(profile, str) else profile
        self.team_name = team_name
        self.key = key
        self.clock = clock
        self.refbox_link = refbox
        self.agents = agents
        self.config = config or ServerConfig()
        self.kb = KnowledgeBase.load(self.profile, Store(state))
        self.refbox = RefboxClient(self.kb, team_name, clock=clock)
        self.link = AgentLink(self.kb, clock)
        self.strategy = make_strategy(self.config.strategy, self.config.seed,
                                      self.config.explore_thresh, oracle)
        self.planner = make_planner(self.config.planner, self.profile, "C",
                                    durations=self.config.durations,
                                    budget=self.config.plan_budget,
                                    max_evaluations=self.config.plan_max_evaluations,
                                    clock=clock,
                                    **({} if self.config.storage is None
                                       else {"storage": self.config.storage}))
        self.production: ProductionManager | None = None
        self.dispatcher: Dispatcher | None = None
        self.reporter: Reporter | None = None
        self.lookout: Lookout | None = None
        self._replan = True
        self._last = {"plan": -1e9, "report": -1e9, "phase": -1e9, "map": -1e9, "beacon": -1e9}
        self._map_bytes = b""
        self.last_choice = None
        self.sent: list = []            # (where, message) of this tick, for tests and logs
        if team_color is not None and self.kb.get("team_color") is None:
            self.kb.set("team_color", team_color.upper())
        # a restarted server: robots must reconnect; give them a full timeout to do so
        for r in self.kb.robots.values():
            r.peer = None
            r.last_heartbeat = clock.now()
        if self.color is not None:
            self._colour_known(self.color)

    # -- properties ----------------------------------------------------------------------
    @property
    def color(self) -> str | None:
        return self.kb.get("team_color")

    def _colour_known(self, color: str) -> None:
        prefix = PREFIX[color]
        self.planner.prefix = prefix
        self.production = ProductionManager(self.kb, self.planner, prefix,
                                            cs_caps=self.config.cs_caps,
                                            max_products=self.config.max_products,
                                            clock=self.clock, prefill=self.config.prefill_caps)
        self.dispatcher = Dispatcher(self.kb, self.production, self.clock, self.config.dispatch)
        self.reporter = Reporter(self.profile, prefix, thresh=self.config.explore_thresh,
                                 margin=self.config.report_margin)
        self.lookout = Lookout(self.profile, prefix, thresh=self.config.explore_thresh)
        if self.refbox_link is not None:
            self.refbox_link.set_team(color, self.key)

    # -- the step -------------------------------------------------------------------------
    def tick(self) -> None:
        """One step: read both links, decide, send.  Never blocks."""
        self.sent = []
        self._read_refbox()
        self._read_agents()
        if self.dispatcher is None:
            self._periodic()
            return
        if self.dispatcher.check_heartbeats():
            self._replan = True
        if self.refbox.running():
            if self._exploration_mode():
                self._explore()
            elif self.refbox.phase == "PRODUCTION":
                self._produce()
        self._flush()
        self._periodic()

    # -- refbox ------------------------------------------------------------------------------
    def _read_refbox(self) -> None:
        if self.refbox_link is None:
            return
        for rx in self.refbox_link.receive():
            for ev in self.refbox.handle(rx.msg):
                self._on_refbox_event(ev)

    def _on_refbox_event(self, ev) -> None:
        if ev.kind == "color":
            log.info("we play %s", ev.data)
            self._colour_known(ev.data)
        elif ev.kind == "phase":
            self._last["phase"] = -1e9          # tell the robots at once
            self._replan = True
            if self.dispatcher is not None and not self._exploration_mode():
                self._end_exploration()
        elif ev.kind == "station":
            name, old, new = ev.data
            if self.production is not None and new == "BROKEN" and old != "BROKEN":
                self.production.station_broke(name)
            if new in ("BROKEN", "DOWN") or old in ("BROKEN", "DOWN"):
                self._replan = True
        elif ev.kind in ("orders", "rings"):
            self._replan = True

    def send_refbox(self, msg) -> None:
        if self.refbox_link is not None:
            self.refbox_link.send(msg)
        self.sent.append(("refbox", msg))

    # -- agents -------------------------------------------------------------------------------
    def _read_agents(self) -> None:
        if self.agents is None:
            return
        for ev in self.agents.events():
            if ev.kind == DISCONNECTED:
                number = self.link.peers.pop(ev.peer, None)
                r = self.kb.robots.get(number) if number is not None else None
                if r is not None:
                    r.peer = None
            elif ev.kind == CONNECTED:
                log.info("agent link from %s", ev.peer)
        for rx in self.agents.receive():
            self._on_agent(rx.msg, rx.source)

    def _on_agent(self, m, peer) -> None:
        name = m.DESCRIPTOR.name
        if name == "RobotHello":
            r = self.link.on_hello(m, peer)
            self._welcome(r)
        elif name == "Heartbeat":
            r, back = self.link.on_heartbeat(m, peer)
            if back:
                self._welcome(r)
        elif name == "RobotStatus":
            r, back = self.link.on_status(m, peer)
            if back:
                self._welcome(r)
            if m.HasField("current_task_id") and r.task_id != m.current_task_id and \
                    m.current_task_id in self.kb.tasks and m.state == BUSY:
                t = self.kb.tasks[m.current_task_id]
                self.send_agent(r, self.link.cancel_msg(M.Task.from_dict(
                    {**t.to_dict(), "robot": r.number}), "task no longer yours"))
        elif name == "TaskResult":
            r = self.link.robot(int(m.robot_id), peer)
            self.link.seen(r)
            if self.dispatcher is not None:
                status = self.link.ms.enum("TaskResult.Status").Name(m.status)
                error = self.link.ms.enum("ErrorCode").Name(m.error)
                holding = m.HasField("holding") if status != "RUNNING" else None
                self.dispatcher.on_result(r.number, int(m.task_id), status, error, holding,
                                          m.text)
                if status in ("FAILED", "SUCCEEDED", "CANCELLED"):
                    self._replan = self._replan or status != "SUCCEEDED"
        elif name == "MachineObservation":
            self.link.on_observation(m)
        elif name == "ZoneExplored":
            self.kb.mark_visited(int(m.zone), self.clock.now())

    def _welcome(self, r: M.Robot) -> None:
        """A robot (re)joined: the game phase, the machine map, and its task at once."""
        log.info("robot %d (%s) is with us", r.number, r.name)
        self.send_agent(r, self._phase_msg())
        self.send_agent(r, self.link.machine_map_msg(consistent_set(self.profile,
                                                                    self.kb.machines)))
        t = self.kb.tasks.get(r.task_id) if r.task_id is not None else None
        if t is not None and t.state == M.ASSIGNED and t.robot == r.number:
            self.send_agent(r, self.link.task_msg(t, self.color))
        self._replan = True

    def send_agent(self, robot: M.Robot | None, msg) -> None:
        """To one robot (by its link), or to all when ``robot`` is None."""
        self.sent.append((robot.number if robot else "all", msg))
        if self.agents is None:
            return
        if robot is None:
            self.agents.send(msg)
        elif robot.peer is not None:
            self.agents.send(msg, to=robot.peer)

    # -- exploration -----------------------------------------------------------------------------
    def _exploration_mode(self) -> bool:
        if not self.refbox.exploring():
            return False
        if self.refbox.phase == "EXPLORATION":
            return True
        # exploring inside PRODUCTION (2017+): until everything is reported
        own = self.profile.machines(self.color)
        reported = self.kb.reported
        return not all(m in reported and "zone" in reported[m] for m in own)

    def exploration_zones(self) -> list[int]:
        zones = self.kb.get("exploration_zones")
        if zones:
            return [int(z) for z in zones]
        return self.profile.machine_zones(self.color)

    def _explore(self) -> None:
        busy = {int(t.params["zone"]) for t in self.kb.open_tasks()
                if t.kind == M.EXPLORE_ZONE and t.state == M.ASSIGNED}
        self._redirect_blind(busy)
        for r in self.dispatcher.idle_robots():
            view = ExplorationView.from_kb(self.kb, self.color, self.exploration_zones(), busy)
            d = self.strategy.next_zone(view, r.pose)
            if d is None:
                continue
            t = self.dispatcher.assign_explore(r, d.zone)
            t.params["branch"] = d.branch
            self.kb.save_task(t)
            busy.add(d.zone)
        now = self.clock.now()
        if now - self._last["report"] >= self.config.report_period:
            self._last["report"] = now
            self.report()

    def _redirect_blind(self, busy: set[int]) -> None:
        """Turn robots away from zones their strategy chose blindly once it has
        a better one for them (``Strategy.redirect``); looked at whenever an
        observation came in.  The freed robots get their new zone at once."""
        blind = [t for t in self.kb.open_tasks() if t.kind == M.EXPLORE_ZONE
                 and t.state == M.ASSIGNED and not is_look(t)]
        if not blind or self._last.get("redirect") == self.kb.observation_count:
            return
        self._last["redirect"] = self.kb.observation_count
        cs = consistent_set(self.profile, self.kb.machines)
        claimed: set[int] = set()
        for t in blind:
            zone = int(t.params["zone"])
            r = self.kb.robots.get(t.robot) if t.robot is not None else None
            view = ExplorationView.from_kb(self.kb, self.color, self.exploration_zones(),
                                           (busy | claimed) - {zone}, cs)
            d = self.strategy.redirect(view, t.params.get("branch"), r.pose if r else None)
            if d is not None:
                self._cancel_explore(t, f"{self.profile.zone_name(d.zone)} was observed")
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
            self.send_refbox(self.refbox.machine_report(entries))
        return entries

    def _end_exploration(self) -> None:
        for t in self.kb.open_tasks():
            if t.kind == M.EXPLORE_ZONE:
                self._cancel_explore(t, "exploration is over")
        self._last["map"] = -1e9

    def _cancel_explore(self, t: M.Task, reason: str) -> None:
        if t.state == M.ASSIGNED:
            self.dispatcher.outbox.append(("cancel", t, reason))
        r = self.kb.robots.get(t.robot) if t.robot is not None else None
        if r is not None and r.task_id == t.id:
            r.task_id = None
            self.kb.save_robot(r)
        t.state = M.CANCELLED
        self.kb.save_task(t)

    def _look_for_rotations(self) -> None:
        """2017+, in the exploration window after every zone is reported: keep
        reporting, and send a robot to look at a station whose rotation is
        still lacking (see :mod:`teamserver.exploration.lookout`)."""
        if not self.refbox.exploring():
            if any(is_look(t) for t in self.kb.open_tasks()):
                self._end_exploration()
            return
        now = self.clock.now()
        if now - self._last["report"] >= self.config.report_period:
            self._last["report"] = now
            self.report()
        cs = self.lookout.consistent(self.kb)
        for t in self.lookout.done_looks(self.kb, cs):
            self._cancel_explore(t, f"the rotation of {t.params[LOOK]} is known")
        for target in self.lookout.targets(self.kb, cs, self.refbox.exploration_left()):
            r = self.lookout.pick_robot(self.dispatcher.available_robots(), target, self.kb)
            if r is None:
                break
            t = self.dispatcher.assign_explore(r, target.zone)
            t.params.update({LOOK: target.machine, "branch": "look",
                             "viewpoints": [list(v) for v in target.viewpoints]})
            self.kb.save_task(t)

    # -- production -----------------------------------------------------------------------------
    def _produce(self) -> None:
        if any(t.kind == M.EXPLORE_ZONE and not is_look(t) for t in self.kb.open_tasks()):
            self._end_exploration()
        now = self.clock.now()
        gt = self.refbox.game_time()
        if self._replan or now - self._last["plan"] >= self.config.replan_period:
            horizon = self.profile.phases.production
            cancels, choice = self.production.plan(gt, horizon)
            for t in cancels:
                self.dispatcher.outbox.append(("cancel", t, "plan repaired"))
            self.last_choice = choice
            self._replan, self._last["plan"] = False, now
        if self.dispatcher.feeds.verify():
            cancels, _ = self.production.plan(gt, self.profile.phases.production)
            for t in cancels:
                self.dispatcher.outbox.append(("cancel", t, "its workpiece was lost"))
            self._last["plan"] = now
        self.dispatcher.feeds.unstick()
        self.dispatcher.release_unusable()
        self.dispatcher.discard_orphans()
        self._look_for_rotations()
        for t in self.dispatcher.assign(gt):
            if t.kind == M.RETRIEVE_CAP:
                n = self.kb.next_id(f"shelf:{t.machine}")
                t.params["shelf_slot"] = (n - 1) % 3
                self.kb.save_task(t)
        self.dispatcher.prepare(self.refbox.running(), gt)
        self.dispatcher.park()

    def _flush(self) -> None:
        for item in self.dispatcher.outbox:
            kind, t = item[0], item[1]
            robot = self.kb.robots.get(t.robot) if t.robot is not None else None
            if kind == "task":
                self.send_agent(robot, self.link.task_msg(t, self.color))
            elif kind == "cancel":
                self.send_agent(robot, self.link.cancel_msg(t, item[2]))
            elif kind == "prepare":
                self.send_refbox(self.refbox.prepare_machine(t.prepare))
        self.dispatcher.outbox.clear()

    # -- periodic messages ------------------------------------------------------------------------
    def _phase_msg(self):
        return self.link.game_phase_msg(self.refbox.phase, self.refbox.state,
                                        self.refbox.game_time(), self.color,
                                        self.refbox.exploring())

    def _periodic(self) -> None:
        now = self.clock.now()
        if now - self._last["phase"] >= self.config.phase_period:
            self._last["phase"] = now
            self.send_agent(None, self._phase_msg())
            for r in self.kb.active_robots():
                if r.peer is not None:
                    self.send_agent(r, self.link.heartbeat_msg(r.number))
        if now - self._last["map"] >= self.config.map_period:
            self._last["map"] = now
            mm = self.link.machine_map_msg(consistent_set(self.profile, self.kb.machines))
            body = b"".join(k.SerializeToString() for k in mm.machines)
            if body != self._map_bytes:
                self._map_bytes = body
                self.send_agent(None, mm)
        if self.config.beacon and now - self._last["beacon"] >= self.config.beacon_period:
            self._last["beacon"] = now
            if self.color is not None:
                self.send_refbox(self.refbox.beacon(self.config.beacon_number))

    # -- status ----------------------------------------------------------------------------------
    def close(self) -> None:
        self.kb.store.close()


__all__ = ["TeamServer", "ServerConfig", "DEFAULT_CS_CAPS", "CYAN", "MAGENTA"]
