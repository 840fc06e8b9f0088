"""The robot agent: team-server link, refbox channels and task trees, stepped, no threads.

    agent = RobotAgent(AgentConfig(robot_id=1, team_name="GRIPS"), clock=clock, backend=robot,
                       link=stream_client, public=public_peer, team=team_peer_or_factory)
    while True: agent.step()        # lockstep: once per simulation step

``step()`` polls every transport, handles what arrived, ticks the task's
tree when a tick is due (``config.hz`` on the agent's clock) and sends what
is due: BeaconSignal to the team server and to the refbox, RobotStatus (and
on every change), MachineObservations as they change, and task results
(the league's AgentTask, :mod:`rll_bt.agenttask`).  A task for a busy robot
waits for the running one, but rll-bt's team server's (with TaskDetail) is refused
unless it was sent to run after that one (:meth:`TaskBook.may_follow`).
"""
from __future__ import annotations

import logging
from typing import Any

from .. import msgs, rules
from ..agenttask import TaskRejected, read_task
from ..backend import Backend, BackendError, Pose2D
from ..clock import Clock
from . import robotstate
from .config import AgentConfig
from .errorcodes import error_code
from .gamestate import GameGate
from .localmap import LocalMachines
from .machinemap import KnownMachines, changed_names, distribute
from .observations import ObservationFeed
from .pose import PoseReader
from .refbox import RefboxLink
from .results import follow_refusal, full_gripper_refusal, make_result
from .runner import InvalidTask, Outcome, TaskRun, default_trees_dir, load_task_tree
from .serverlink import ServerLink
from .stations import StationStates
from .taskbook import Entry, TaskBook

log = logging.getLogger("rll_bt.agent")


class RobotAgent:
    """One robot's mid-level.

    ``clock``: the agent's time; ``backend``: the robot; ``link``: the
    team-server transport (a stream client of :mod:`rll_bt.agenttask.link`);
    ``public``: the refbox public-channel transport (or None); ``team``: the
    refbox team-channel transport, or a factory ``team(color)`` making it
    once the colour is known (or None); ``services``: shared objects for
    the trees (the agent adds ``observations`` and, once known,
    ``machine_map``); ``registry``: node registry (default: all installed
    node types); ``start_pose``: field pose at start, for odometry-based poses.
    """

    def __init__(self, config: AgentConfig, *, clock: Clock, backend: Backend | None, link,
                 public=None, team=None, services: dict[str, Any] | None = None, registry=None,
                 start_pose: Pose2D | None = None, restarted: bool = True):
        self.config = config
        self.clock = clock
        self.backend = backend
        self.registry = registry
        self.profile = rules.profile(config.profile)
        self.tm = msgs.message_set("team")
        self.rm = msgs.message_set(config.profile)
        self.trees_dir = config.trees_dir or default_trees_dir()
        self.server = ServerLink(link, config, clock, restarted=restarted)
        self.gate = GameGate(config.team_name, clock, config.game_state_fresh, config.require_game)
        self.refbox = RefboxLink(self.rm, clock, config.robot_id, config.team_name, config.peer_name, public, team)
        self.feed = ObservationFeed(self.profile, clock, config.robot_id)
        self.services: dict[str, Any] = services if services is not None else {}
        self.services.setdefault("observations", self.feed)
        self.stations = self.services.setdefault("refbox_stations", StationStates())
        self.services.setdefault("profile", self.profile)
        self.services.setdefault("robot_number", config.robot_id)
        if start_pose is not None:
            self.services.setdefault("start_pose", start_pose)
        self._n_services = len(self.services)
        self.pose = PoseReader(backend, self.services, start_pose)
        self.book = TaskBook()
        self.run: TaskRun | None = None
        self.machines: KnownMachines | None = None
        self.local = LocalMachines(self.profile) if config.league_only else None
        self.map_updates = 0
        self._details: dict[int, Any] = {}          # task id -> TaskDetail not yet matched
        self._moving: bool | None = None
        self.fault: str | None = None
        self._status_sig: tuple | None = None
        now = clock.now()
        self._next_tick = now
        self._next_hb = now
        self._read_at = now                     # when the link to the team server was last read
        self._next_status = now
        self._next_beacon = now
        self.observers: list = []    # stepped(agent), task_started(agent, run), task_ended(agent, run, outcome)
        if config.color:
            self._set_color(config.color)
        self.feed.attach_services(self.services.values())

    # -- compatibility views --------------------------------------------------------------
    @property
    def link(self):
        return self.server.t

    @property
    def connected(self) -> bool:
        return self.server.connected

    @property
    def registrations(self) -> int:
        return self.server.registrations

    @property
    def server_silent(self) -> bool:
        return self.server.silent

    @property
    def finished(self):
        """task id -> :class:`~.taskbook.Result` of the tasks that ended."""
        return self.book.finished

    # -- the loop ---------------------------------------------------------------------
    def step(self) -> None:
        """Poll, handle, tick if due, send what is due.  Never blocks."""
        for rec in self.server.poll(self._on_connect):
            try:
                self._on_server_message(rec.msg)
            except Exception:       # a message the agent chokes on must not stop the robot's loop
                log.exception("robot %d: handling %s failed", self.config.robot_id, rec.type_name)
        self._read_at = self.clock.now()        # the link read up to here (see _periodic)
        self._poll_refbox()
        self._apply_gate()
        now = self.clock.now()
        if now >= self._next_tick:
            period = self.config.tick_period
            self._next_tick += period
            if self._next_tick <= now:
                self._next_tick = now + period
            self.tick()
        self._periodic(self.clock.now())
        self.server.step()
        self._flush()
        self._notify("stepped")

    def _notify(self, what: str, *args) -> None:
        for obs in self.observers:
            try:
                getattr(obs, what, lambda *a: None)(self, *args)
            except Exception:       # an observer must never stop the robot
                log.exception("robot %d: observer %r failed in %s", self.config.robot_id, obs, what)

    def moving_allowed(self) -> bool:
        """The game lets the robot move and its task is not paused."""
        cur = self.book.current
        return self.gate.moving_allowed and not (cur is not None and cur.paused)

    def tick(self) -> Outcome | None:
        """Tick the current task's tree once, if there is one and the robot may move
        (its lease runs out also while it stands); returns the outcome when the task ended."""
        run, now, lease = self.run, self.clock.now(), self.server.lease
        if run is None or run.done or not (self.moving_allowed() or lease.expired(now)):
            return None
        outcome = lease.tick(run, now, self.moving_allowed())     # past its lease it stops (.lease)
        if len(self.services) != self._n_services:     # a node made a service on first use
            self._services_changed()
        if outcome is not None:
            self._finish(run, outcome)
        return outcome

    def next_due(self) -> float:
        """Clock time of the next tick or periodic message."""
        return min(self._next_tick, self._next_hb, self._next_status, self._next_beacon)

    def wait(self, max_seconds: float) -> None:
        """Block until the next duty or until the team-server link has data
        (wall-clock runs; a lockstep run never calls this)."""
        left = max(0.0, min(max_seconds, self.next_due() - self.clock.now()))
        if left > 0:
            self.server.wait(left)

    # -- team-server link -----------------------------------------------------------------
    def _on_connect(self) -> None:
        self._send_status(force=True)
        if self.server.league_only:
            self._beacon_to_server()

    def _on_server_message(self, m) -> None:
        name = m.DESCRIPTOR.name
        if name == "AgentTask":
            self._on_agent_task(m)
        elif name == "TaskDetail":
            self._details[int(m.task_id)] = m
            while len(self._details) > 64:
                self._details.pop(next(iter(self._details)))
        elif name == "MachineMap":
            self._on_machine_map(KnownMachines.from_message(m, self.clock.now()))
        elif name == "GamePhase":
            self.gate.on_game_phase(m)
            self._follow_color()
        elif name != "Heartbeat":
            log.debug("robot %d: ignoring %s from the team server", self.config.robot_id, name)

    def _on_agent_task(self, at) -> None:
        me, tid = self.config.robot_id, int(at.task_id)
        detail = self._details.pop(tid, None)
        if at.HasField("cancel_task") and at.cancel_task:
            self._on_cancel(at)
            return
        where = self.book.where(tid)
        if at.HasField("pause_task") and where in ("current", "waiting"):
            self._on_pause(at, where)
            return
        if where == "finished" and self.book.given_again(tid, detail):
            self.book.forget(tid)                           # cancelled, then given out again: a new run
            where = None
        elif where == "finished":
            self.server.again(self.book.result(tid))        # already done: tell again
            return
        if where is not None:
            return                                          # sent again while it runs or waits
        after = int(detail.after) if detail is not None and detail.HasField("after") else None
        if detail is not None and self.run is not None and not self.run.done and after != self.run.task_id:
            busy = f"robot {me} is busy with task {self.run.task_id}; cancel it first"   # rll-bt's server replans
            return self.server.result(make_result(at, robot_id=me, status="FAILED", code="INVALID_TASK", text=busy,
                                                  holding=self._holding(), stamp=self.clock.now()))
        try:
            kind, params = read_task(at, detail, profile=self.profile, robot_id=me, color=self.color(),
                                     machines=self.machines)
        except TaskRejected as exc:
            log.warning("robot %d: task %d rejected: %s", me, tid, exc)
            self._record(make_result(at, robot_id=me, status="FAILED", code="INVALID_TASK", text=exc.text,
                                     league_code=exc.code, holding=self._holding(),
                                     stamp=self.clock.now(), team_color=self._team_value()))
            return
        entry = Entry(at, detail, kind, params, paused=bool(at.pause_task))
        if self.book.may_follow(entry) is False:                # sent to run after a task that failed
            return self._record(follow_refusal(entry, self._holding(), robot_id=me, stamp=self.clock.now()))
        if self.book.take(entry):
            self._start(entry)
        else:
            log.info("robot %d: task %d %s waits for task %d", me, tid, kind, self.book.current.task_id)

    def _start(self, entry: Entry) -> None:
        """Load and start the tree of ``entry`` (the book's current task)."""
        me, tid, kind, params = self.config.robot_id, entry.task_id, entry.kind, entry.params
        refusal = full_gripper_refusal(entry, self._holding(), robot_id=me, stamp=self.clock.now())
        if refusal is not None:
            log.warning("robot %d: task %d %s refused: the gripper holds a workpiece", me, tid, kind)
            self._record(refusal)
            self._start_next()
            return
        try:
            if self.trees_dir is None:
                raise InvalidTask("no trees directory (give --trees)")
            tree = load_task_tree(self.trees_dir, kind, params, backend=self.backend, clock=self.clock,
                                  services=self.services, registry=self.registry)
        except ValueError as exc:
            log.warning("robot %d: task %d rejected: %s", me, tid, exc)
            self._record(make_result(entry.task, robot_id=me, status="FAILED", code="INVALID_TASK",
                                     text=str(exc), league_code="TASK_NOT_SUPPORTED",
                                     holding=self._holding(), stamp=self.clock.now()))
            self._start_next()
            return
        if len(self.services) != self._n_services:      # the tree's services were made just now
            self._services_changed()
        self.run = TaskRun(entry.task, params, tree, self.clock, max_gap=max(0.5, 5 * self.config.tick_period))
        self._notify("task_started", self.run)
        log.info("robot %d: task %d %s %s", me, tid, kind,
                 {k: v for k, v in params.items() if k not in ("task_id", "robot_id", "kind")})
        self._send_status(force=True)

    def _start_next(self) -> None:
        nxt = self.book.next()
        while nxt is not None and self.book.may_follow(nxt) is False:     # its predecessor failed
            self._record(follow_refusal(nxt, self._holding(), robot_id=self.config.robot_id, stamp=self.clock.now()))
            nxt = self.book.next()
        if nxt is not None and (self.run is None or self.run.task_id != nxt.task_id):
            self._start(nxt)

    def _on_cancel(self, at) -> None:
        tid = int(at.task_id)
        if int(at.robot_id) != self.config.robot_id:
            return
        where = self.book.where(tid)
        run = self.run
        if where == "current" and run is not None and run.task_id == tid and not run.done:
            log.info("robot %d: task %d cancelled", self.config.robot_id, tid)
            self._finish(run, run.cancel("cancelled by the team server"))
        elif where == "waiting":
            entry = self.book.drop_waiting(tid)
            self._record(make_result(entry.task, robot_id=self.config.robot_id, status="CANCELLED",
                                     text="cancelled before it started", stamp=self.clock.now()))
        elif where == "finished":
            self.server.result(self.book.result(tid))
        else:
            result = make_result(at, robot_id=self.config.robot_id, status="CANCELLED",
                                 text="cancelled before it arrived", stamp=self.clock.now())
            if self.server.server_speaks_rllbt:
                # its ids name one assignment each: a copy of the task that comes after its cancel
                # (reordered, repeated) is refused (a league server may give the same id out again)
                self._record(result)
            else:
                self.server.result(result)

    def _on_pause(self, at, where: str) -> None:
        entry = self.book.entry(int(at.task_id))
        entry.paused = bool(at.pause_task)
        entry.task.pause_task = entry.paused
        log.info("robot %d: task %d %s", self.config.robot_id, entry.task_id,
                 "paused" if entry.paused else "resumed")

    def _on_machine_map(self, known: KnownMachines) -> None:
        old, self.machines = self.machines, known
        self.map_updates += 1
        self.machines.updates = self.map_updates
        took = distribute(self.services, self.machines, changed_names(old, self.machines))
        log.info("robot %d: machine map with %d stations (%d services took it)", self.config.robot_id,
                 len(self.machines), took)

    # -- refbox ---------------------------------------------------------------------------------
    def _poll_refbox(self) -> None:
        for rec in self.refbox.receive():
            name = rec.msg.DESCRIPTOR.name
            if name == "GameState":
                self.gate.on_game_state(rec.msg)
                self._follow_color()
            elif name == "MachineInfo":
                self.stations.update(rec.msg, self.clock.now())
                if self.local is not None and self.local.on_machine_info(rec.msg):
                    self._on_machine_map(self.local.known())

    def color(self) -> str | None:
        """Our team colour: as configured, else as the refbox (or the team server) says."""
        return self.config.color or self.gate.color

    def _team_value(self) -> int | None:
        c = self.color()
        return ("CYAN", "MAGENTA").index(c) if c else None

    def _set_color(self, color: str) -> None:
        self.refbox.set_color(color)
        self.server.color = color

    def _follow_color(self) -> None:
        color = self.color()
        if color and color != self.refbox.color:
            self._set_color(color)

    def _apply_gate(self) -> None:
        moving = self.moving_allowed()
        if moving == self._moving:
            return
        self._moving = moving
        if not moving:
            log.info("robot %d: standing still (%s)", self.config.robot_id,
                     self.gate.describe() if not self.gate.moving_allowed else "task paused")
            if self.run is not None and not self.run.done:
                self.run.halt()
            self._stop_robot()
        else:
            log.info("robot %d: game running (%s)", self.config.robot_id, self.gate.describe())
            self._next_tick = self.clock.now()
        self._send_status(force=True)

    # -- results and status ----------------------------------------------------------------
    def _finish(self, run: TaskRun, outcome: Outcome) -> None:
        self._stop_robot()
        code = "NONE"
        text = outcome.text
        if outcome.status != "SUCCEEDED":
            _value, code = error_code(outcome.code)
            if code != str(outcome.code).upper():
                text = f"{outcome.code}: {text}" if text else str(outcome.code)
        if outcome.status == "SUCCEEDED" and run.kind == "explore_zone" and \
                int(run.params["zone"]) not in self.feed.searched:
            found = run.tree.outputs().get("found")         # explore_zone.yaml's declared output
            self.feed.zone_searched(int(run.params["zone"]), found if isinstance(found, list) else None)
        holding = self._holding()
        result = make_result(run.task, robot_id=self.config.robot_id, status=outcome.status, code=code, text=text,
                             holding=holding, stamp=self.clock.now())
        self._notify("task_ended", run, outcome)
        log.info("robot %d: task %d %s %s%s", self.config.robot_id, run.task_id, run.kind, outcome.status,
                 f" {code} {text}" if code != "NONE" else "")
        self.run = None
        self._record(result)
        self._send_status(force=True)
        self._start_next()

    def _record(self, result) -> None:
        self.book.finish(int(result.task.task_id), result)
        self.server.result(result)

    def _holding(self) -> bool | None:
        return robotstate.holding(self.backend)

    def state(self) -> str:
        """The RobotStatus state: FAULT, STOPPED, RECOVERING, BUSY or IDLE."""
        if self.fault:
            return "FAULT"
        if not self.moving_allowed():
            return "STOPPED"
        if self.run is not None and not self.run.done:
            return "RECOVERING" if self.run.recovering else "BUSY"
        return "IDLE"

    def _send_status(self, force: bool = False) -> None:
        if not self.server.extras:
            return
        state = self.state()
        task_id = self.run.task_id if self.run is not None else None
        waiting = getattr(self.stations, "waiting", None) if task_id is not None else None
        sig = (state, task_id, waiting)
        if not force and sig == self._status_sig and self.clock.now() < self._next_status:
            return
        if not self.server.connected:
            return
        pose, conf = self.pose.read()
        st = self.server.status_msg(state, pose, conf, task_id, bool(self._holding()))
        robotstate.fill_battery(st, self.backend)
        if waiting:
            st.waiting_at = waiting
        if self.server.send(st):
            self._status_sig = sig
            self._next_status = self.clock.now() + self.config.status_period

    def _periodic(self, now: float) -> None:
        c = self.config
        if now >= self._next_hb:
            self._next_hb = now + c.heartbeat_period
            if self.server.connected:
                self._beacon_to_server()
            # silent since the last read of the link, not since before a long tick: a robot held up
            # (a loaded machine, a slow backend call) finds what came meanwhile at its next read
            self.server.check_silence(min(now, self._read_at))
        if now >= self._next_status:
            self._send_status(force=True)
            self._next_status = max(self._next_status, now + c.status_period)
        else:
            self._send_status()
        if now >= self._next_beacon:
            self._next_beacon = now + c.beacon_period
            pose, _conf = self.pose.read()
            self.refbox.beacon(pose, *self.book.beacon_tasks(self.config.beacon_finished))

    def _beacon_to_server(self) -> None:
        pose, _conf = self.pose.read()
        self.server.send(self.server.beacon(pose, *self.book.beacon_tasks(self.config.beacon_finished)))

    def _flush(self) -> None:
        if not len(self.feed) or not (self.server.connected or self.local is not None):
            return
        pending = self.feed.drain()
        if self.local is not None:
            if self.local.on_observations(pending):
                self._on_machine_map(self.local.known())
            return
        for i, m in enumerate(pending):
            if not self.server.send(m):
                self.feed.requeue(pending[i:])
                return

    # -- robot -------------------------------------------------------------------------------
    def _stop_robot(self) -> None:
        if self.backend is None:
            return
        try:
            self.backend.stop()
            self.fault = None
        except BackendError as exc:
            self.fault = f"cannot stop the robot: {exc}"
            log.error("robot %d: %s", self.config.robot_id, self.fault)

    def _services_changed(self) -> None:
        """New services exist: let them feed observations and give them the machine map."""
        self._n_services = len(self.services)
        self.feed.attach_services(self.services.values())     # those that publish sightings feed the stream
        if self.machines is not None:
            distribute(self.services, self.machines)

    # -- life cycle ---------------------------------------------------------------------------
    def shutdown(self, reason: str = "agent shut down") -> None:
        """Stop the robot and report a running task as failed (INTERNAL)."""
        self.book.waiting.clear()
        run = self.run
        if run is not None and not run.done:
            run.halt()
            self._finish(run, Outcome("FAILED", "INTERNAL", reason))
        self._stop_robot()
        self._flush()

    def close(self) -> None:
        """:meth:`shutdown`, then close the link and the refbox channels."""
        try:
            self.shutdown()
        finally:
            self.server.close()
            self.refbox.close()
