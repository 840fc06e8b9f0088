"""The robot agent: team-server link, refbox channels and task trees in one
stepped object with no threads.

    agent = RobotAgent(AgentConfig(robot_id=1, team_name="GRIPS"), clock=clock, backend=robot,
                       link=stream_client, public=public_peer, team=team_peer_or_factory)
    while True:
        agent.step()            # lockstep: once per simulation step

``step()`` polls every transport, handles what arrived, ticks the task's
tree when a tick is due (``config.hz`` on the agent's clock) and sends what
is due: Heartbeat, RobotStatus (and on every change), BeaconSignal,
MachineObservations as they change, and task results.  See the package
docstring for the messages in each direction.
"""
from __future__ import annotations

import logging
from collections import OrderedDict, deque
from typing import Any

from .. import msgs, rules
from ..backend import Backend, BackendError, Pose2D
from ..clock import Clock
from ..comm import CONNECTED, DISCONNECTED
from . import robotstate
from .config import AgentConfig
from .delivery import ServerDelivery
from .errorcodes import error_code
from .gamestate import GameGate
from .machinemap import KnownMachines, changed_names, distribute
from .observations import ObservationFeed
from .pose import PoseReader
from .refbox import RefboxLink
from .runner import Outcome, TaskRun, default_trees_dir, load_task_tree
from .stations import StationStates
from .tasks import InvalidTask, agent_task, task_kind, task_params

log = logging.getLogger("rll_bt.agent")

KEEP_FINISHED = 1024    # results remembered to answer re-sent tasks and cancels


class RobotAgent:
    """One robot's mid-level.

    ``clock``: the agent's time; ``backend``: the robot; ``link``: the
    team-server transport (:class:`~rll_bt.comm.StreamClient` or a bus stream
    client, encrypted with the team key, registry of the ``team`` message
    set); ``public``: the refbox public-channel transport (or None);
    ``team``: the refbox team-channel transport, or a factory
    ``team(color)`` making it once the colour is known (or None);
    ``services``: shared objects for the trees (the agent adds
    ``observations`` and, once received, ``machine_map``);
    ``registry``: node registry (default: all installed node types);
    ``start_pose``: field pose at start, for odometry-based poses.
    """

    def __init__(self, config: AgentConfig, *, clock: Clock, backend: Backend | None, link,
                 public=None, team=None, services: dict[str, Any] | None = None, registry=None,
                 start_pose: Pose2D | None = None, restarted: bool = True):
        self.config = config
        self.clock = clock
        self.backend = backend
        self.link = link
        self.registry = registry
        self.profile = rules.profile(config.profile)
        self.tm = msgs.message_set("team")
        self.rm = msgs.message_set(config.profile)
        self.trees_dir = config.trees_dir or default_trees_dir()
        self.gate = GameGate(config.team_name, clock, config.game_state_fresh, config.require_game)
        self.refbox = RefboxLink(self.rm, clock, config.robot_id, config.team_name, config.peer_name, public, team)
        self.feed = ObservationFeed(self.profile, clock, config.robot_id)
        self.services: dict[str, Any] = services if services is not None else {}
        self.services.setdefault("observations", self.feed)
        self.stations = self.services.setdefault("refbox_stations", StationStates())
        self.services.setdefault("profile", self.profile)
        if start_pose is not None:
            self.services.setdefault("start_pose", start_pose)
        self._n_services = len(self.services)
        self.pose = PoseReader(backend, self.services, start_pose)
        self.run: TaskRun | None = None
        self.machines: KnownMachines | None = None
        self.map_updates = 0
        self.finished: OrderedDict[int, Any] = OrderedDict()     # task id -> final TaskResult
        self._issued: dict[int, float] = {}     # task id -> issued_at of the task as this robot ran it
        self._beacon_finished: deque[list] = deque(maxlen=32)    # [task_id, ok, beacons left]
        self.delivery = ServerDelivery(link, clock, lambda: self.tm.LinkAck(robot_id=config.robot_id))
        self._restarted_next = restarted
        self._hello_due = False
        self.connected = False
        self.registrations = 0
        self.last_server_rx: float | None = None
        self.server_silent = False
        self._moving: bool | None = None
        self.fault: str | None = None
        self._status_sig: tuple | None = None
        self._hb_seq = 0
        now = clock.now()
        self._next_tick = now
        self._next_hb = now
        self._next_status = now
        self._next_beacon = now
        self._attached: set[int] = set()
        self.observers: list = []    # stepped(agent), task_started(agent, run), task_ended(agent, run, outcome)
        if config.color:
            self.refbox.set_color(config.color)
        if getattr(link, "connected", False):
            self._hello_due = True
        self._attach_observers()

    # -- the loop ---------------------------------------------------------------------
    def step(self) -> None:
        """Poll, handle, tick if due, send what is due.  Never blocks."""
        self._poll_link()
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
        self.delivery.step(self.connected)
        self._flush()
        self._notify("stepped")

    def _notify(self, what: str, *args) -> None:
        for obs in self.observers:
            try:
                getattr(obs, what, lambda *a: None)(self, *args)
            except Exception:       # an observer must never stop the robot
                log.exception("robot %d: observer %r failed in %s", self.config.robot_id, obs, what)

    def tick(self) -> Outcome | None:
        """Tick the current task's tree once, if there is one and the game
        lets the robot move; returns the outcome when the task ended."""
        run = self.run
        if run is None or run.done or not self.gate.moving_allowed:
            return None
        outcome = run.tick()
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
            self.link.wait(left)

    # -- team-server link -----------------------------------------------------------------
    def _poll_link(self) -> None:
        for ev in self.link.events():
            if ev.kind == CONNECTED:
                self.connected = True
                self._hello_due = True
                log.info("robot %d: connected to the team server", self.config.robot_id)
            elif ev.kind == DISCONNECTED:
                self.connected = False
                self._hello_due = False
                log.warning("robot %d: team server link lost; reconnecting", self.config.robot_id)
        if self._hello_due and getattr(self.link, "connected", True):
            self._hello()
        for rec in self.link.receive():
            self.last_server_rx = self.clock.now()
            self.server_silent = False
            if not self.delivery.incoming(rec.msg):
                continue                        # an acknowledgement
            try:
                self._on_server_message(rec.msg)
            except Exception:       # a message the agent chokes on must not stop the robot's loop
                log.exception("robot %d: handling %s failed", self.config.robot_id, rec.type_name)

    def _hello(self) -> None:
        c = self.config
        hello = self.tm.RobotHello(robot_id=c.robot_id, team_name=c.team_name, peer_name=c.peer_name,
                                   capabilities=list(c.capabilities), restarted=self._restarted_next)
        if self.color():
            hello.team_color = self.tm.enum("TeamColor").Value(self.color())
        if self.link.send(hello):
            self.connected = True
            self._hello_due = False
            self._restarted_next = False
            self.registrations += 1
            self.last_server_rx = self.clock.now()
            self._send_status(force=True)
            if self.run is not None and not self.run.done:
                self._send(self._result(self.run.task_id, "RUNNING"))
            self.delivery.reconnected()         # final results the server has not acknowledged

    def _on_server_message(self, m) -> None:
        name = m.DESCRIPTOR.name
        if name == "Task":
            self._on_task(m)
        elif name == "CancelTask":
            self._on_cancel(m)
        elif name == "MachineMap":
            self._on_machine_map(m)
        elif name == "GamePhase":
            self.gate.on_game_phase(m)
            self._follow_color()
        elif name != "Heartbeat":
            log.debug("robot %d: ignoring %s from the team server", self.config.robot_id, name)

    def _on_task(self, task) -> None:
        me = self.config.robot_id
        tid = int(task.task_id)
        if int(task.robot_id) != me:
            log.warning("robot %d: ignoring task %d for robot %d", me, tid, task.robot_id)
            return
        if self.run is not None and self.run.task_id == tid:
            self._send(self._result(tid, "RUNNING"))           # the server re-sent it: still on it
            return
        if tid in self.finished and self._given_again(tid, task):
            del self.finished[tid]                             # cancelled, then given out again: a new run
        elif tid in self.finished:
            self._send(self.finished[tid])                     # already done: tell again
            return
        if self.run is not None and not self.run.done:
            self._send(self._result(tid, "FAILED", "INVALID_TASK",
                                    f"robot {me} is busy with task {self.run.task_id}; cancel it first"))
            return
        try:
            kind = task_kind(task)
            params = task_params(task, self.profile)
            if kind == "report_machines":
                self._report_machines(task, params)
                return
            if self.trees_dir is None:
                raise InvalidTask("no trees directory (give --trees)")
            tree = load_task_tree(self.trees_dir, kind, params, backend=self.backend, clock=self.clock,
                                  services=self.services, registry=self.registry)
        except (InvalidTask, ValueError) as exc:
            log.warning("robot %d: task %d rejected: %s", me, tid, exc)
            self._record(tid, self._result(tid, "FAILED", "INVALID_TASK", str(exc)), ok=False)
            return
        if len(self.services) != self._n_services:      # the tree's services were made just now
            self._services_changed()
        self.run = TaskRun(task, params, tree, self.clock, max_gap=max(0.5, 5 * self.config.tick_period))
        self._issued[tid] = float(task.issued_at)
        self._notify("task_started", self.run)
        log.info("robot %d: task %d %s %s", me, tid, kind,
                 {k: v for k, v in params.items() if k not in ("task_id", "robot_id", "kind")})
        self._send(self._result(tid, "RUNNING"))
        self._send_status(force=True)

    def _report_machines(self, task, params) -> None:
        tid = int(task.task_id)
        try:
            sent = self.refbox.machine_report(params["entries"])
        except ValueError as exc:           # e.g. a zone the refbox's Zone enum does not have
            raise InvalidTask(f"cannot build the MachineReport: {exc}") from None
        if sent:
            result = self._result(tid, "SUCCEEDED")
        else:
            result = self._result(tid, "FAILED", "INTERNAL", "no refbox team channel (colour unknown?)")
        self._record(tid, result, ok=result.status == self.tm.TaskResult.SUCCEEDED)

    def _on_cancel(self, c) -> None:
        tid = int(c.task_id)
        if int(c.robot_id) != self.config.robot_id:
            return
        run = self.run
        if run is not None and run.task_id == tid and not run.done:
            log.info("robot %d: task %d cancelled (%s)", self.config.robot_id, tid, c.reason or "no reason given")
            self._finish(run, run.cancel(c.reason))
        elif tid in self.finished:
            self._send(self.finished[tid])
        else:
            self._send(self._result(tid, "CANCELLED", "CANCELLED", "no such task on this robot"))

    def _on_machine_map(self, m) -> None:
        old, self.machines = self.machines, KnownMachines.from_message(m, self.clock.now())
        self.map_updates += 1
        self.machines.updates = self.map_updates
        took = distribute(self.services, self.machines, changed_names(old, self.machines))
        log.info("robot %d: machine map with %d stations (%d services took it)", self.config.robot_id,
                 len(self.machines), took)

    # -- refbox ---------------------------------------------------------------------------------
    def _poll_refbox(self) -> None:
        for rec in self.refbox.receive():
            if rec.msg.DESCRIPTOR.name == "GameState":
                self.gate.on_game_state(rec.msg)
                self._follow_color()
            elif rec.msg.DESCRIPTOR.name == "MachineInfo":
                self.stations.update(rec.msg, self.clock.now())

    def color(self) -> str | None:
        """Our team colour: as configured, else as the refbox (or the team server) says."""
        return self.config.color or self.gate.color

    def _follow_color(self) -> None:
        color = self.color()
        if color and color != self.refbox.color:
            self.refbox.set_color(color)

    def _apply_gate(self) -> None:
        moving = self.gate.moving_allowed
        if moving == self._moving:
            return
        self._moving = moving
        if not moving:
            log.info("robot %d: standing still (%s)", self.config.robot_id, self.gate.describe())
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
            value, code = error_code(outcome.code)
            if code != str(outcome.code).upper():
                text = f"{outcome.code}: {text}" if text else str(outcome.code)
        if outcome.status == "SUCCEEDED" and run.kind == "explore_zone" and \
                int(run.params["zone"]) not in self.feed.searched:
            found = run.tree.outputs().get("found")         # explore_zone.yaml's declared output
            self.feed.zone_searched(int(run.params["zone"]), found if isinstance(found, list) else None)
        result = self._result(run.task_id, outcome.status, code, text)
        self._notify("task_ended", run, outcome)
        log.info("robot %d: task %d %s %s%s", self.config.robot_id, run.task_id, run.kind, outcome.status,
                 f" {code} {text}" if code != "NONE" else "")
        self.run = None
        self._record(run.task_id, result, ok=outcome.status == "SUCCEEDED")
        self._send_status(force=True)

    def _given_again(self, tid: int, task) -> bool:
        """``task`` gives out again a task the server cancelled on this robot (issued after that run)."""
        result = self.finished[tid]
        return result.status == self.tm.TaskResult.CANCELLED and \
            float(task.issued_at) > self._issued.get(tid, float("inf"))

    def _record(self, tid: int, result, ok: bool) -> None:
        self.finished[tid] = result
        while len(self.finished) > KEEP_FINISHED:
            self._issued.pop(self.finished.popitem(last=False)[0], None)
        self._beacon_finished.append([tid, ok, self.config.finished_beacons])
        self.delivery.send_final(result, self.connected)

    def _result(self, tid: int, status: str, code: str = "NONE", text: str = ""):
        r = self.tm.TaskResult(task_id=tid, robot_id=self.config.robot_id,
                               status=self.tm.TaskResult.Status.Value(status),
                               error=self.tm.enum("ErrorCode").Value(code), stamp=self.clock.now())
        if text:
            r.text = text[:500]
        if status != "RUNNING":
            holding = self._holding()
            if holding:
                r.holding.SetInParent()
        return r

    def _holding(self) -> bool | None:
        return robotstate.holding(self.backend)

    def state(self) -> str:
        """The RobotStatus state: FAULT, STOPPED, RECOVERING, BUSY or IDLE."""
        if self.fault:
            return "FAULT"
        if not self.gate.moving_allowed:
            return "STOPPED"
        if self.run is not None and not self.run.done:
            return "RECOVERING" if self.run.recovering else "BUSY"
        return "IDLE"

    def _send_status(self, force: bool = False) -> None:
        state = self.state()
        task_id = self.run.task_id if self.run is not None else None
        waiting = getattr(self.stations, "waiting", None) if task_id is not None else None
        sig = (state, task_id, waiting)
        if not force and sig == self._status_sig and self.clock.now() < self._next_status:
            return
        if not self.connected:
            return
        c = self.config
        st = self.tm.RobotStatus(robot_id=c.robot_id, state=self.tm.RobotStatus.State.Value(state),
                                 stamp=self.clock.now())
        pose, conf = self.pose.read()
        if pose is not None:
            st.pose.x, st.pose.y, st.pose.theta = pose.x, pose.y, pose.theta
            st.pose_confidence = conf
        if task_id is not None:
            st.current_task_id = task_id
        if self._holding():
            st.holding.SetInParent()
        robotstate.fill_battery(st, self.backend)
        if waiting:
            st.waiting_at = waiting
        if self.link.send(st):
            self._status_sig = sig
            self._next_status = self.clock.now() + c.status_period

    def _periodic(self, now: float) -> None:
        c = self.config
        if now >= self._next_hb:
            self._next_hb = now + c.heartbeat_period
            if self.connected:
                self._hb_seq += 1
                self.link.send(self.tm.Heartbeat(robot_id=c.robot_id, seq=self._hb_seq, stamp=now))
            if self.connected and self.last_server_rx is not None and \
                    now - self.last_server_rx > c.server_timeout and not self.server_silent:
                self.server_silent = True
                log.warning("robot %d: nothing from the team server for %.1f s; reconnecting",
                            c.robot_id, now - self.last_server_rx)
                reconnect = getattr(self.link, "reconnect", None)
                if reconnect is not None:
                    reconnect()
        if now >= self._next_status:
            self._send_status(force=True)
            self._next_status = max(self._next_status, now + c.status_period)
        else:
            self._send_status()
        if now >= self._next_beacon:
            self._next_beacon = now + c.beacon_period
            self._beacon()

    def _beacon(self) -> None:
        pose, _conf = self.pose.read()
        task = None
        run = self.run
        if run is not None and not run.done and self.refbox.color:
            task = agent_task(self.rm, run.task, run.params, self.profile, self.refbox.color)
        finished = [(e[0], e[1]) for e in self._beacon_finished]
        if self.refbox.beacon(pose, task, finished):
            for e in self._beacon_finished:
                e[2] -= 1
            while self._beacon_finished and self._beacon_finished[0][2] <= 0:
                self._beacon_finished.popleft()

    def _flush(self) -> None:
        if not self.connected or not len(self.feed):
            return
        pending = self.feed.drain()
        for i, m in enumerate(pending):
            if not self.link.send(m):
                self.feed.requeue(pending[i:])
                return

    def _send(self, msg) -> bool:
        return bool(self.connected and self.link.send(msg))

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
        self._attach_observers()
        if self.machines is not None:
            distribute(self.services, self.machines)

    def _attach_observers(self) -> None:
        """Let services that publish sightings (``subscribe``) feed the observation stream."""
        for svc in list(self.services.values()):
            for src in (svc, getattr(svc, "machines", None)):
                if src is None or src is self.feed or id(src) in self._attached:
                    continue
                if callable(getattr(src, "subscribe", None)) and self.feed.attach(src):
                    self._attached.add(id(src))

    # -- life cycle ---------------------------------------------------------------------------
    def shutdown(self, reason: str = "agent shut down") -> None:
        """Stop the robot and report a running task as failed (INTERNAL)."""
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
            self.link.close()
            self.refbox.close()
