"""A scripted team server, a refbox on bus or UDP peers, test node types and a
rig that steps an agent on a simulated clock (for the rll_bt.agent tests)."""
from __future__ import annotations

import time
from pathlib import Path

from py_trees.common import Status

from backends.scripted import ScriptedBackend
from rll_bt import msgs
from rll_bt.agent import AgentConfig, RobotAgent
from rll_bt.clock import SimClock
from rll_bt.comm import CONNECTED, DISCONNECTED, MessageRegistry, StreamServer
from rll_bt.tree import Input, Node, default_registry

TEAM, KEY = "Testers", "s3cret-key"
TM = msgs.message_set("team")
TEAM_REG = MessageRegistry.from_message_set(TM)
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

def make_task(kind: str, task_id: int = 1, robot: int = 1, color: int = 0, timeout: float | None = None, **fields):
    """A team-protocol Task of ``kind`` with the given body fields."""
    t = TM.Task(team_color=color, task_id=task_id, robot_id=robot)
    body = getattr(t, kind)
    body.SetInParent()
    for k, v in fields.items():
        if isinstance(v, list):
            getattr(body, k).extend(v)
        elif hasattr(v, "DESCRIPTOR"):
            getattr(body, k).CopyFrom(v)
        else:
            setattr(body, k, v)
    if timeout is not None:
        t.timeout = timeout
    return t


class ScriptedServer:
    """Records what agents send; answers a RobotHello with GamePhase and MachineMap."""

    def __init__(self, transport, machines=(("C-CS1", 1.5, 3.0, 0.0), ("C-BS", 5.0, 0.75, 1.57)),
                 state="RUNNING", phase="PRODUCTION", color=0):
        self.t = transport
        self.machines = list(machines)
        self.state, self.phase, self.color = state, phase, color
        self.got: list[tuple[object, object]] = []      # (client, msg)
        self.events: list = []
        self.client = None
        self.pumps = 0
        self.heartbeat_every = 20       # pumps between the server's heartbeats

    def pump(self) -> None:
        self.pumps += 1
        if self.client is not None and self.pumps % self.heartbeat_every == 0:
            self.send(TM.Heartbeat(robot_id=0, seq=self.pumps))
        for ev in self.t.events():
            self.events.append(ev)
            if ev.kind == CONNECTED:
                self.client = ev.peer
            elif ev.kind == DISCONNECTED and ev.peer == self.client:
                self.client = None
        for rx in self.t.receive():
            self.got.append((rx.source, rx.msg))
            if rx.msg.DESCRIPTOR.name == "RobotHello":
                self.client = rx.source
                self.send_phase()
                self.send_map()

    def of(self, name: str) -> list:
        return [m for _c, m in self.got if m.DESCRIPTOR.name == name]

    def results(self, task_id: int | None = None, status: str | None = None) -> list:
        out = []
        for r in self.of("TaskResult"):
            if task_id is not None and r.task_id != task_id:
                continue
            if status is not None and TM.TaskResult.Status.Name(r.status) != status:
                continue
            out.append(r)
        return out

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

    def task(self, task_id: int, kind: str, robot: int = 1, timeout: float | None = None, **fields) -> None:
        assert self.send(make_task(kind, task_id, robot, self.color, timeout, **fields))

    def cancel(self, task_id: int, robot: int = 1) -> None:
        assert self.send(TM.CancelTask(task_id=task_id, robot_id=robot, reason="test"))


def tcp_server(port: int = 0, key: str = KEY) -> StreamServer:
    return StreamServer(port, host="127.0.0.1", registry=TEAM_REG, key=key)


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
        """Once the game runs, send a task and round until the robot says RUNNING."""
        self.until(lambda: self.agent.gate.moving_allowed, what="game running")
        self.server.task(task_id, kind, **fields)
        self.until(lambda: self.server.results(task_id, "RUNNING"), what=f"task {task_id} RUNNING")

    def drives(self) -> list[tuple]:
        """(t, method) of the base commands, in order."""
        return [(t, m) for t, m, _a in self.backend.commands if m in ("drive", "stop")]
