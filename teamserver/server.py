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

The server composes; the deciding is done by its collaborators, built once
our colour is known (:meth:`TeamServer._colour_known`): the
:class:`~teamserver.exploration.explorer.Explorer`, the
:class:`~teamserver.production.manager.ProductionManager`, the
:class:`~teamserver.production.feeding.FeedMonitor` and the
:class:`~teamserver.dispatch.dispatcher.Dispatcher`, all telling the robots
and the refbox about tasks through one
:class:`~teamserver.links.tasks.TaskLink`.  See ``docs/architecture.md``.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from pathlib import Path

from rll_bt import rules
from rll_bt.clock import Clock
from rll_bt.comm.transport import CONNECTED, DISCONNECTED
from rll_bt.rules import CYAN, MAGENTA, PREFIX, Profile

from .dispatch.config import DispatchConfig
from .dispatch.dispatcher import Dispatcher
from .exploration.explorer import Explorer
from .exploration.lights import LightGate
from .exploration.lookout import Lookout
from .exploration.report import Reporter
from .exploration.strategies import DEFAULT_THRESH, make_strategy
from .exploration.symmetry import consistent_set
from .knowledge import model as M
from .knowledge.kb import KnowledgeBase
from .knowledge.store import Store
from .links.agents import AgentLink, from_wire
from .links.refbox import RefboxClient
from .links.tasks import TaskLink
from .planning.estimate import Durations
from .planning.planner import StoragePolicy, make_planner
from .production.feeding import FeedMonitor
from .production.manager import ProductionManager

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
    robots: str = "rll-bt"                      # "agenttask": robots of the league (AgentTask only)
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
        if self.config.dispatch.stuck_timeout is None and self.profile.stuck_timeout is not None:
            self.config = replace(self.config, dispatch=replace(
                self.config.dispatch, stuck_timeout=self.profile.stuck_timeout))
        self.kb = KnowledgeBase.load(self.profile, Store(state))
        self.refbox = RefboxClient(self.kb, team_name, clock=clock)
        self.link = AgentLink(self.kb, clock, extras=self.config.robots != "agenttask")
        self.tasks = TaskLink(self.kb, self.link, self.refbox, self.send_agent, self.send_refbox)
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
        self.explorer: Explorer | None = None
        self._replan = True
        self._last = {"plan": -1e9, "report": -1e9, "phase": -1e9, "map": -1e9, "beacon": -1e9}
        self._map_bytes = b""
        self.last_choice = None
        self.sent: list = []            # (where, message) of this tick, for tests and logs
        if team_color is not None and self.kb.get("team_color") is None:
            self.kb.set("team_color", team_color.upper())
        # a restarted server: robots must reconnect; give them a full timeout to do so, and
        # take it that each may hold the longest lease this server grants (.links.leases)
        for r in self.kb.robots.values():
            r.peer = None
            r.last_heartbeat = clock.now()
            self.link.leases.restarted(r.number, self.config.dispatch.heartbeat_timeout, clock.now())
        if self.color is not None:
            self._colour_known(self.color)

    # -- properties ----------------------------------------------------------------------
    @property
    def color(self) -> str | None:
        return self.kb.get("team_color")

    def _colour_known(self, color: str) -> None:
        """Our colour is known: build production, dispatch and exploration for it."""
        prefix = PREFIX[color]
        cfg = self.config
        self.planner.prefix = prefix
        self.production = ProductionManager(self.kb, self.planner, prefix, cs_caps=cfg.cs_caps,
                                            max_products=cfg.max_products, clock=self.clock,
                                            prefill=cfg.prefill_caps)
        feeds = FeedMonitor(self.kb, self.clock, self.production.repairs,
                            self.production.cleanup, cfg.dispatch.feed_confirm)
        self.dispatcher = Dispatcher(self.kb, self.production, feeds, self.clock, self.tasks,
                                     cfg.dispatch)
        self.explorer = Explorer(
            self.kb, self.clock, self.strategy,
            Reporter(self.profile, prefix, thresh=cfg.explore_thresh, margin=cfg.report_margin,
                     lights=LightGate(self.kb)),
            Lookout(self.profile, prefix, thresh=cfg.explore_thresh), self.refbox,
            self.dispatcher.fleet, self.tasks, self.send_refbox,
            report_period=cfg.report_period, on_end=self._map_now)
        self.dispatcher.readiness.unfound = self.explorer.unfound
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
        if self.dispatcher.dropouts.check_heartbeats():
            self._replan = True
        if self.refbox.running():
            exploring = self.explorer.active()
            if exploring:
                self.explorer.explore()
            if self.refbox.phase == "PRODUCTION" and (not exploring or self.explorer.beside()):
                self._produce(exploring)
        self.tasks.flush()
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
            if self.dispatcher is not None and not self.explorer.active():
                self.explorer.end()
        elif ev.kind == "station":
            name, old, new = ev.data
            if self.production is not None and new == "BROKEN" and old != "BROKEN":
                self.production.repairs.station_broke(name)
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
                number = self.link.dropped(ev.peer)
                r = self.kb.robots.get(number) if number is not None else None
                if r is not None:
                    r.peer = None
            elif ev.kind == CONNECTED:
                log.info("agent link from %s", ev.peer)
        for rx in self.agents.receive():
            self._on_agent(rx.msg, rx.source)

    def _on_agent(self, m, peer) -> None:
        if not self.tasks.incoming(m):
            if m.DESCRIPTOR.name == "AgentTask":
                self.link.drop_outcome(m)     # a result acted on already: its TaskOutcome came again too
            return
        name = m.DESCRIPTOR.name
        if name == "RobotHello":
            r = self.link.on_hello(m, peer)
            self._welcome(r)
        elif name == "BeaconSignal":
            r, back = self.link.on_beacon(m, peer)
            if back:
                self._welcome(r)
            if not self.link.speaks_rllbt(r):
                self._league_beacon(r, m)
        elif name == "RobotStatus":
            r, back = self.link.on_status(m, peer)
            if back:
                self._welcome(r)
            if m.HasField("current_task_id") and m.state == BUSY:
                self._not_yours(r, int(m.current_task_id))
        elif name == "TaskOutcome":
            self.link.on_outcome(m)
        elif name == "AgentTask" and (m.HasField("successful") or m.HasField("canceled")):
            r = self.link.robot(int(m.robot_id), peer)
            self.link.seen(r)
            status, error, holding, text = self.link.result_of(m)
            t = self.link.task_of(int(m.task_id))
            if t is None:
                log.info("robot %d: result of assignment %d, which is over", r.number, m.task_id)
            else:
                self._result(r, t.id, status, error, holding, text)
        elif name == "MachineObservation":
            self.link.on_observation(m)
        elif name == "ZoneExplored":
            self.kb.mark_visited(int(m.zone), self.clock.now())

    def _result(self, r: M.Robot, task_id: int, status: str, error: str, holding: bool | None,
                text: str) -> None:
        """A task's result from robot ``r``, to the dispatcher."""
        if self.dispatcher is None:
            return
        self.dispatcher.results.on_result(r.number, task_id, status, error, holding, text)
        self._replan = self._replan or status != "SUCCEEDED"

    def _not_yours(self, r: M.Robot, wire: int) -> None:
        """``r`` runs an assignment the server has not given it (any more): cancel it there."""
        tid, _attempt = from_wire(wire)
        if tid not in self.kb.tasks:
            return
        t = self.link.task_of(wire)
        if t is None or (r.task_id != t.id and not (t.state == M.ASSIGNED and t.robot == r.number)):  # (queued)
            self.send_agent(r, self.link.cancel_wire(wire, r.number, self.color))

    def _league_beacon(self, r: M.Robot, m) -> None:
        """A league robot's beacon says what it runs and what it finished: a task
        it runs that is not its own is cancelled; a finished one still assigned
        to it counts as its result (when the echoed AgentTask did not come); a
        task cancelled on it that it does not run any more is stopped."""
        self.tasks.runs(r.number, int(m.task.task_id) if m.HasField("task") else None)
        if m.HasField("task"):
            self._not_yours(r, int(m.task.task_id))
        for f in m.finished_tasks:
            t = self.link.task_of(int(f.TaskId))
            if t is not None and t.state == M.ASSIGNED and t.robot == r.number:
                self._result(r, t.id, "SUCCEEDED" if f.successful else "FAILED",
                             "NONE", None, "reported in the robot's beacon")

    def _welcome(self, r: M.Robot) -> None:
        """A robot (re)joined: the game phase and the machine map (to a robot that
        speaks rll-bt), and its task at once."""
        log.info("robot %d (%s) is with us", r.number, r.name)
        if self.link.speaks_rllbt(r):
            self.send_agent(r, self._phase_msg())
            self.send_agent(r, self.link.machine_map_msg(consistent_set(self.profile,
                                                                        self.kb.machines)))
        self.tasks.welcome(r)
        self._replan = True

    def send_agent(self, robot: M.Robot | None, msg) -> None:
        """To one robot (by its link), or, an rll-bt addition, to every robot that
        speaks rll-bt when ``robot`` is None."""
        if robot is None and not self.link.extras:
            return
        self.sent.append((robot.number if robot else "all", msg))
        if self.agents is None:
            return
        if robot is None and not self.link.league_peers:
            self.agents.send(msg)
        elif robot is None:
            for peer in sorted(self.link.rllbt_peers):
                self.agents.send(msg, to=peer)
        elif robot.peer is not None:
            self.agents.send(msg, to=robot.peer)

    # -- production -----------------------------------------------------------------------------
    def _produce(self, exploring: bool = False) -> None:
        """A production step; ``exploring``: beside exploration's tail (its tasks stay,
        no looks for rotations yet)."""
        d, pm = self.dispatcher, self.production
        if not exploring and self.explorer.exploring_blindly():
            self.explorer.end()
        now = self.clock.now()
        gt = self.refbox.game_time()
        if self._replan or now - self._last["plan"] >= self.config.replan_period:
            horizon = self.profile.phases.production
            cancels, choice = pm.plan(gt, horizon)
            for t in cancels:
                self.tasks.cancel(t, "plan repaired")
                d.fleet.took_back(t)        # a pickup: no new work until it says what it holds
            self.last_choice = choice
            self._replan, self._last["plan"] = False, now
        if d.feeds.verify():
            cancels, _ = pm.plan(gt, self.profile.phases.production)
            for t in cancels:
                self.tasks.cancel(t, "its workpiece was lost")
                d.fleet.took_back(t)        # a pickup: no new work until it says what it holds
            self._last["plan"] = now
        d.feeds.unstick()
        d.dropouts.release_unusable()
        d.fleet.settle_queued()         # queued behind a task taken back or cancelled: back to the pool
        d.discards.discard_orphans()
        if not exploring:
            self.explorer.look_for_rotations()
        for t in d.matcher.assign(gt):
            if t.kind == M.RETRIEVE_CAP:
                pm.caps.choose_shelf_slot(t)
        if pm.caps.prefill_caps and d.fleet.idle_for() >= self.config.dispatch.idle_prefill:
            pm.caps.prefill(gt, self.profile.phases.production)     # work for a robot without
        d.preparer.prepare(self.refbox.running(), gt)
        d.parking.park()

    # -- periodic messages ------------------------------------------------------------------------
    def _map_now(self) -> None:
        """Send the machine map at the end of this tick if it changed."""
        self._last["map"] = -1e9

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
                if r.peer is not None and self.link.speaks_rllbt(r):
                    self.send_agent(r, self.link.heartbeat_msg(r.number, self.config.dispatch.heartbeat_timeout))
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
