"""A scripted team server, a refbox on bus or UDP peers, test node types and a
rig that steps an agent on a simulated clock (for the rll_bt.agent tests)."""
from __future__ import annotations

import time
from pathlib import Path

from py_trees.common import Status

from backends.scripted import ScriptedBackend
from rll_bt import msgs
from rll_bt.agent import AgentConfig, RobotAgent
from rll_bt.agenttask import link as agent_link
from rll_bt.clock import SimClock
from rll_bt.comm import CONNECTED, DISCONNECTED, StreamServer
from rll_bt.tree import Input, Node, default_registry

TEAM, KEY = "Testers", "s3cret-key"
TM = msgs.message_set("team")
LM = msgs.message_set("rcll2025")
TEAM_REG = agent_link.registry()
TREES = Path(__file__).parent / "agent_trees"


# -- node types only the agent tests use ---------------------------------------------------

class TestDrive(Node):
    """Drive forward at ``speed`` for ``seconds`` (0: until halted); stops the base when done or halted."""
    speed = Input(float, "m/s", default=0.2)
    seconds = Input(float, "how long; 0 drives until halted", default=0.0)

    def initialise(self):
        self.starts = getattr(self, "starts", 0) + 1
        self._until = self.ctx.clock.now() + float(self.seconds)
        self.ctx.backend.drive(float(self.speed), 0.0, 0.0)

    def update(self):
        if self.seconds and self.ctx.clock.now() >= self._until:
            return Status.SUCCESS
        return Status.RUNNING

    def terminate(self, new_status):
        if new_status in (Status.INVALID, Status.SUCCESS):
            self.ctx.backend.stop()


class TestSighting(Node):
    """Report a station sighting to the ``observations`` service."""
    machine = Input(str, "station name")
    x = Input(float, "m")
    y = Input(float, "m")
    lights = Input(int, "light pattern", default=0)
    requires_services = ("observations",)

    def update(self):
        from rll_bt.backend import Pose2D
        self.ctx.service("observations").machine(self.machine, pose=Pose2D(self.x, self.y, 0.0),
                                                 lights=self.lights or None, confidence=0.8)
        return Status.SUCCESS


class TestCrash(Node):
    """Raise an exception (a bug in a node)."""

    def update(self):
        raise RuntimeError("node bug")


class TestSensorLost(Node):
    """The laser goes away under the running task (the backend raises SensorLost)."""

    def update(self):
        from rll_bt.backend import SensorLost
        raise SensorLost("laser", "laser lost: no scan for more than 0.5 s")


REGISTRY = default_registry().child()
REGISTRY.register(TestDrive, "test_drive")
REGISTRY.register(TestSighting, "test_sighting")
REGISTRY.register(TestCrash, "test_crash")
REGISTRY.register(TestSensorLost, "test_sensor_lost")


# -- the scripted team server -----------------------------------------------------------------

def make_task(kind: str, task_id: int = 1, robot: int = 1, color: int = 0, timeout: float | None = None,
              profile: str = "rcll2016", **params):
    """``(AgentTask, TaskDetail)`` of an rll-bt task ``kind`` with ``params`` (as
    rll-bt's team server plans them: ``machine``, ``side`` "SLIDE", ``ring_color``
    "RING_BLUE", ``zone``, go_to's ``x``/``y``/``theta`` ...)."""
    from rll_bt import rules
    from rll_bt.agenttask import render_task
    if timeout is not None:
        params["timeout"] = timeout
    return render_task(kind, params, task_id=task_id, robot_id=robot, color=("CYAN", "MAGENTA")[color],
                       profile=rules.profile(profile))


class Res:
    """A result as the scripted server saw it: the echoed AgentTask and the TaskOutcome before it."""

    def __init__(self, task, outcome):
        self.task, self.outcome = task, outcome
        self.task_id, self.robot_id = int(task.task_id), int(task.robot_id)
        self.status = "CANCELLED" if task.canceled else "SUCCEEDED" if task.successful else "FAILED"
        self.league_code = int(task.error_code) if task.HasField("error_code") else None
        if outcome is not None:
            self.code = TM.ErrorCode.Name(outcome.error)
            self.text, self.stamp = outcome.text, outcome.stamp
            self.holding = outcome.holding if outcome.HasField("holding") else None
        else:
            from rll_bt.agenttask import from_league
            self.code, self.text, self.stamp, self.holding = from_league(self.league_code), "", None, None

    def __repr__(self) -> str:
        return f"Res({self.task_id} {self.status} {self.code} {self.text!r})"


class ScriptedServer:
    """Records what agents send; answers a RobotHello with GamePhase and MachineMap.
    ``league``: send tasks as a league team server does (AgentTask only)."""

    def __init__(self, transport, machines=(("C-CS1", 1.5, 3.0, 0.0), ("C-BS", 5.0, 0.75, 1.57)),
                 state="RUNNING", phase="PRODUCTION", color=0, league=False, profile="rcll2016"):
        self.t = transport
        self.profile = profile
        self.machines = list(machines)
        self.state, self.phase, self.color = state, phase, color
        self.league = league
        self.got: list[tuple[object, object]] = []      # (client, msg)
        self.events: list = []
        self.client = None
        self.pumps = 0
        self.heartbeat_every = 20       # pumps between the server's heartbeats
        self.lease: float | None = None  # give the robot a task lease of so many s (rll_bt.agent.lease)
        self.heard: float | None = None  # the latest stamp of the robot's statuses
        self.leases = None               # grant leases as rll-bt's team server does (follow_leases)
        self.last_heard: float | None = None     # ... when the robot was last heard (server clock)
        self.given_away: float | None = None     # ... when the server could first give its task away
        self.granted: list[tuple[float, float]] = []    # ... (heard, lease) of its heartbeats
        self._outcomes: dict[int, object] = {}
        self._results: list[Res] = []

    def pump(self) -> None:
        self.pumps += 1
        if self.client is not None and self.pumps % self.heartbeat_every == 0 and not self.league:
            hb = TM.Heartbeat(robot_id=0, seq=self.pumps)
            granted = self.leases.grant(1, self.timeout) if self.leases is not None else None
            if granted is not None:
                hb.heard, hb.lease = granted
                self.granted.append(granted)
            elif self.lease is not None and self.heard is not None:
                hb.heard, hb.lease = self.heard, self.lease
            self.send(hb)
        for ev in self.t.events():
            self.events.append(ev)
            if ev.kind == CONNECTED:
                self.client = ev.peer
            elif ev.kind == DISCONNECTED and ev.peer == self.client:
                self.client = None
        for rx in self.t.receive():
            self.got.append((rx.source, rx.msg))
            name = rx.msg.DESCRIPTOR.name
            if self.leases is not None:
                self.last_heard = self.clock.now()
                if name == "RobotHello":
                    self.leases.reset(1)
                elif name == "RobotStatus":
                    self.leases.status(1, rx.msg.stamp if rx.msg.HasField("stamp") else None,
                                       rx.msg.lease_lag if rx.msg.HasField("lease_lag") else None,
                                       self.clock.now())
            if name == "RobotHello":
                self.client = rx.source
                self.send_phase()
                self.send_map()
            elif name == "RobotStatus" and rx.msg.HasField("stamp"):
                self.heard = max(rx.msg.stamp, self.heard if self.heard is not None else rx.msg.stamp)
            elif name == "TaskOutcome":
                self._outcomes[int(rx.msg.task_id)] = rx.msg
            elif name == "AgentTask" and (rx.msg.HasField("successful") or rx.msg.HasField("canceled")):
                self._results.append(Res(rx.msg, self._outcomes.pop(int(rx.msg.task_id), None)))
        if self.leases is not None and self.given_away is None and self.last_heard is not None and \
                self.leases.past(1, self.last_heard, self.timeout, self.clock.now()):
            self.given_away = self.clock.now()

    def follow_leases(self, clock, timeout: float = 10.0) -> None:
        """Grant robot 1 task leases as rll-bt's team server does (teamserver.links.leases,
        drop timeout ``timeout``) and note in :attr:`given_away` when its task could first
        go to another robot (silent ``timeout`` s and past every lease granted)."""
        from teamserver.links.leases import Leases
        self.leases, self.clock, self.timeout = Leases(), clock, timeout

    def of(self, name: str) -> list:
        return [m for _c, m in self.got if m.DESCRIPTOR.name == name]

    def results(self, task_id: int | None = None, status: str | None = None) -> list[Res]:
        return [r for r in self._results if (task_id is None or r.task_id == task_id)
                and (status is None or r.status == status)]

    def final(self, task_id: int) -> Res | None:
        out = self.results(task_id)
        return out[-1] if out else None

    def running(self, task_id: int) -> bool:
        """A beacon (or status) said the robot runs ``task_id``."""
        return any(b.HasField("task") and b.task.task_id == task_id for b in self.of("BeaconSignal")) or \
            any(s.HasField("current_task_id") and s.current_task_id == task_id for s in self.of("RobotStatus"))

    def send(self, msg) -> bool:
        return self.t.send(msg, to=self.client) if self.client is not None else False

    def send_phase(self, state: str | None = None, phase: str | None = None) -> None:
        self.state, self.phase = state or self.state, phase or self.phase
        self.send(TM.GamePhase(state=TM.GamePhase.State.Value(self.state), phase=TM.GamePhase.Phase.Value(self.phase),
                               game_time=1.0, team_color=self.color))

    def send_map(self) -> None:
        mm = TM.MachineMap(profile="rcll2016", stamp=1.0)
        for name, x, y, th in self.machines:
            k = mm.machines.add(name=name, type=name[2:4], team_color=0, zone=1)
            k.pose.x, k.pose.y, k.pose.theta = x, y, th
        self.send(mm)

    def task(self, task_id: int, kind: str, robot: int = 1, timeout: float | None = None, detail: bool = True,
             after: int | None = None, **params) -> None:
        """Send a task: AgentTask, after its TaskDetail unless ``detail`` is False
        or the server is a league one; ``after``: to run once that task succeeded."""
        at, d = make_task(kind, task_id, robot, self.color, timeout, profile=self.profile, **params)
        if after is not None:
            d.after = after
        if detail and not self.league:
            assert self.send(d)
        assert self.send(at)

    def send_agent_task(self, at) -> None:
        assert self.send(at)

    def cancel(self, task_id: int, robot: int = 1) -> None:
        from rll_bt.agenttask import render_cancel
        assert self.send(render_cancel(task_id, robot, ("CYAN", "MAGENTA")[self.color]))


def tcp_server(port: int = 0, key: str | None = KEY) -> StreamServer:
    return agent_link.tcp_server(port, host="127.0.0.1", key=key)


# -- stepping ---------------------------------------------------------------------------------

class Rig:
    """An agent on a scripted backend, stepped with a scripted server on one SimClock."""

    def __init__(self, link, server: ScriptedServer, clock: SimClock | None = None, *, backend=None,
                 public=None, team=None, dt: float = 0.05, real_wait: float = 0.0, restarted: bool = True,
                 services=None, registry=REGISTRY, **config):
        self.clock = clock or SimClock()
        self.backend = backend or ScriptedBackend(clock=self.clock)
        self.server = server
        self.dt, self.real_wait = dt, real_wait
        cfg = {"robot_id": 1, "team_name": TEAM, "trees_dir": TREES}
        cfg.update(config)
        self.agent = RobotAgent(AgentConfig(**cfg), clock=self.clock, backend=self.backend, link=link,
                                public=public, team=team, registry=registry, restarted=restarted,
                                services=services)
        self.extra: list = []           # more things to step each round (callables)

    def round(self) -> None:
        self.agent.step()
        if self.real_wait:
            time.sleep(self.real_wait)
        if self.server is not None:
            self.server.pump()
        for fn in self.extra:
            fn()
        self.clock.advance(self.dt)

    def run(self, seconds: float) -> None:
        end = self.clock.now() + seconds
        while self.clock.now() < end:
            self.round()

    def until(self, pred, seconds: float = 10.0, what: str = "condition", min_wall: float = 5.0) -> None:
        """Round until ``pred()``; fail after ``seconds`` of sim time (and, over
        real sockets, at least ``min_wall`` seconds of real time)."""
        end = self.clock.now() + seconds
        wall_end = time.monotonic() + (min_wall if self.real_wait else 0.0)
        while not pred():
            if self.clock.now() >= end and time.monotonic() >= wall_end:
                raise AssertionError(f"{what} not reached within {seconds} s of sim time")
            self.round()

    def start_task(self, task_id: int, kind: str, **fields) -> None:
        """Once the game runs, send a task and round until the robot says it runs it."""
        self.until(lambda: self.agent.gate.moving_allowed, what="game running")
        self.server.task(task_id, kind, **fields)
        self.until(lambda: self.server.running(task_id), what=f"task {task_id} running")

    def drives(self) -> list[tuple]:
        """(t, method) of the base commands, in order."""
        return [(t, m) for t, m, _a in self.backend.commands if m in ("drive", "stop")]
