"""Scripted refbox and robots for the team-server tests (lockstep, one clock)."""
from __future__ import annotations

from types import SimpleNamespace

from rll_bt import msgs, rules
from rll_bt.agenttask import link as agent_link
from rll_bt.agenttask import read_task
from rll_bt.clock import SimClock
from rll_bt.comm import Bus, MessageRegistry, StreamClient
from rll_bt.comm.reliable import Reliable
from teamserver.links.agents import from_wire
from teamserver.links.refbox_link import RefboxLink
from teamserver.server import ServerConfig, TeamServer

TEAM, KEY = "Testers", "secret"
PHASE = {"PRE_GAME": 0, "SETUP": 10, "EXPLORATION": 20, "PRODUCTION": 30, "POST_GAME": 40}
STATE = {"INIT": 0, "WAIT_START": 1, "RUNNING": 2, "PAUSED": 3}


class FakeRefbox:
    """Speaks the profile's refbox messages on bus peers: public + cyan."""

    def __init__(self, bus: Bus, profile: str):
        self.ms = msgs.message_set(profile)
        reg = MessageRegistry.from_message_set(self.ms)
        self.public = bus.peer("public", registry=reg, name="refbox")
        self.cyan = bus.peer("cyan", registry=reg, key=KEY, name="refbox")
        self.received: list = []

    def game_state(self, phase="PRODUCTION", state="RUNNING", t=0.0, team=TEAM):
        gs = self.ms.GameState(state=STATE[state], phase=PHASE[phase], team_cyan=team)
        gs.game_time.sec, gs.game_time.nsec = int(t), int((t % 1) * 1e9)
        self.public.send(gs)

    def orders(self, orders):
        info = self.ms.OrderInfo()
        for o in orders:
            info.orders.add(**o)
        self.public.send(info)

    def rings(self, costs):
        e = self.ms.enum("RingColor")
        info = self.ms.RingInfo()
        for c, n in costs.items():
            info.rings.add(ring_color=e.Value(c), raw_material=n)
        self.cyan.send(info)

    def machines(self, states: dict, ring_colors: dict | None = None, **extra):
        info = self.ms.MachineInfo(team_color=0)
        e = self.ms.enum("RingColor")
        for name, state in states.items():
            m = info.machines.add(name=name, state=state, type=name[2:4])
            for c in (ring_colors or {}).get(name, ()):
                m.ring_colors.append(e.Value(c))
            for k, v in extra.get(name, {}).items():
                setattr(m, k, v)
        self.cyan.send(info)

    def take(self):
        got = [rx.msg for rx in self.cyan.receive()]
        self.received += got
        return got


class TaskView:
    """A task as a robot reads it (:func:`rll_bt.agenttask.read_task` of the
    AgentTask and the TaskDetail before it): ``task_id`` (the team server's
    task; ``wire_id`` the assignment's id on the wire), ``kind``
    (``WhichOneof("kind")``), the parameters as ``view.<kind>.<name>``, and
    the messages themselves (``agent_task``, ``detail``)."""

    def __init__(self, at, detail, profile):
        self.agent_task, self.detail = at, detail
        self.wire_id, self.robot_id, self.team_color = int(at.task_id), int(at.robot_id), int(at.team_color)
        self.task_id = from_wire(self.wire_id)[0]
        self.kind, self.params = read_task(at, detail, profile=profile, robot_id=at.robot_id)
        setattr(self, self.kind, SimpleNamespace(**{k: SimpleNamespace(**v) if isinstance(v, dict) else v
                                                    for k, v in self.params.items()}))

    def WhichOneof(self, _name: str) -> str:     # the protobuf name the tests use
        return self.kind


class FakeAgent:
    """A robot agent speaking rll-bt over the team-server link: the league's
    AgentTask and BeaconSignal plus rll-bt's additions; with ``league`` a robot
    of the league: no hello, no status, only beacons (pose, ``running`` task)."""

    def __init__(self, transport, number: int, pose=(4.0, 0.5, 0.0), profile="rcll2016", ack: bool = True,
                 league: bool = False):
        self.ms = msgs.message_set("team")
        self.lm = msgs.message_set("rcll2025")
        self.profile = rules.profile(profile)
        self.t = transport
        self.number = number
        self.pose = pose
        self.inbox: list = []
        self.seq = 0
        self.league = league
        self.running = None                  # the AgentTask a league robot says it runs (beacon field 9)
        self.ack = ack and not league        # acknowledge tasks and cancels, as an rll-bt agent does
        self.link = Reliable(SimClock())
        self.acks: list = []                 # LinkAcks the server sent
        self._views: list[TaskView] = []
        self._details: dict[int, object] = {}

    def hello(self, restarted=False):
        if self.league:
            return self.beat()
        self.t.send(self.ms.RobotHello(robot_id=self.number, team_name=TEAM,
                                       peer_name=f"robot{self.number}", restarted=restarted))

    def beat(self):
        self.seq += 1
        b = self.lm.BeaconSignal(seq=self.seq, number=self.number, team_name=TEAM, peer_name=f"robot{self.number}")
        b.time.sec, b.time.nsec = 0, 0
        b.pose.x, b.pose.y, b.pose.ori = self.pose
        b.pose.timestamp.sec, b.pose.timestamp.nsec = 0, 0
        if self.running is not None:
            b.task.CopyFrom(self.running)
        self.t.send(b)

    def status(self, state=1, holding=False, waiting_at=None, task=None, stamp=None, lag=None):
        """rll-bt's RobotStatus (``task``: the wire id of the assignment it says it runs;
        ``stamp``, ``lag``: its clock's time and the lag of its lease confirmations)."""
        if self.league:
            return self.beat()
        st = self.ms.RobotStatus(robot_id=self.number, state=state)
        if stamp is not None:
            st.stamp = stamp
        if lag is not None:
            st.lease_lag = lag
        if task is not None:
            st.current_task_id = int(task)
        st.pose.x, st.pose.y, st.pose.theta = self.pose
        if holding:
            st.holding.SetInParent()
        if waiting_at:
            st.waiting_at = waiting_at
        self.t.send(st)

    def take(self):
        got = [rx.msg for rx in self.t.receive()]
        if self.ack:
            self.acks += [m for m in got if m.DESCRIPTOR.name == "LinkAck"]
            got = [m for m in got if m.DESCRIPTOR.name != "LinkAck"]
            for m in got:
                self.link.received("server", m)
            for _, ack in self.link.acks(lambda _s: self.ms.LinkAck(robot_id=self.number)):
                self.t.send(ack)
        self.inbox += got
        for m in got:
            if m.DESCRIPTOR.name == "TaskDetail":
                self._details[int(m.task_id)] = m
            elif m.DESCRIPTOR.name == "AgentTask" and not m.cancel_task:
                self._views.append(TaskView(m, self._details.pop(int(m.task_id), None), self.profile))
        return got

    def tasks(self):
        """Tasks with real work (parking GO_TOs: :meth:`parks`)."""
        return [v for v in self._views if v.kind != "go_to"]

    def parks(self):
        """GO_TO tasks (parking) this robot got."""
        return [v for v in self._views if v.kind == "go_to"]

    def cancels(self):
        """The cancels it got (``task_id``: the team server's task, ``wire_id``)."""
        return [SimpleNamespace(task_id=from_wire(m.task_id)[0], wire_id=int(m.task_id))
                for m in self.inbox if m.DESCRIPTOR.name == "AgentTask" and m.cancel_task]

    def result(self, task_id, status="SUCCEEDED", error="NONE", holding=None, text=""):
        """The robot's result (of the last assignment of the team server's task
        ``task_id`` it got): rll-bt's TaskOutcome (with the skill's ``text``), then
        the echoed AgentTask."""
        from rll_bt.agenttask import league_value, to_league
        task_id = next((v.wire_id for v in reversed(self._views) if v.task_id == task_id), task_id)
        code = error if status != "CANCELLED" else "CANCELLED"
        out = self.ms.TaskOutcome(task_id=task_id, robot_id=self.number, error=self.ms.enum("ErrorCode").Value(code))
        if holding:
            out.holding = True
        if text:
            out.text = text
        at = self.lm.AgentTask(team_color=0, task_id=task_id, robot_id=self.number,
                               successful=status == "SUCCEEDED", canceled=status == "CANCELLED")
        if status == "FAILED":
            at.error_code = league_value(to_league(error))
        self.t.send(out)
        self.t.send(at)

    def observe(self, name, zone=None, zconf=0.9, lights=None, lconf=0.9, orientation=None,
                oconf=0.9, pose=None, pconf=0.9):
        m = self.ms.MachineObservation(robot_id=self.number)
        m.name.value, m.name.confidence = name, 1.0
        if zone is not None:
            m.zone.value, m.zone.confidence = zone, zconf
        if lights is not None:
            m.lights.pattern, m.lights.confidence = lights, lconf
        if orientation is not None:
            m.orientation.value, m.orientation.confidence = orientation, oconf
        if pose is not None:
            m.pose.pose.x, m.pose.pose.y, m.pose.pose.theta = pose
            m.pose.confidence = pconf
        self.t.send(m)


class Lockstep:
    """A team server, a fake refbox and fake agents on one bus and one clock."""

    def __init__(self, profile="rcll2016", robots=3, state=":memory:", config=None,
                 tcp=False, league=False, **kw):
        self.tcp = tcp
        self.clock = SimClock()
        self.bus = Bus(self.clock)
        self.profile_name = profile
        self.profile = rules.profile(profile)
        self.refbox = FakeRefbox(self.bus, profile)
        self.state = state
        self.config = config or ServerConfig()
        self.kw = kw
        self.team_reg = agent_link.registry()
        self.server = self._server()
        self.agents = [FakeAgent(self._client(f"robot{i}"), i, profile=profile, league=league)
                       for i in range(1, robots + 1)]
        if tcp:
            for a in self.agents:
                assert a.t.wait_connected(5.0), "loopback TCP connect failed"

    def _client(self, name):
        if self.tcp:
            return StreamClient("127.0.0.1", self.server.agents.port, registry=self.team_reg,
                                key=KEY, clock=self.clock)
        return self.bus.stream_client("teamserver", registry=self.team_reg, key=KEY, name=name)

    def _server(self):
        reg = MessageRegistry.from_message_set(msgs.message_set(self.profile_name))
        link = RefboxLink(self.bus.peer("public", registry=reg, name="ts"),
                          lambda color: self.bus.peer(color, registry=reg, name="ts"))
        if self.tcp:
            agents = agent_link.tcp_server(0, host="127.0.0.1", key=KEY, clock=self.clock)
        else:
            agents = agent_link.bus_server(self.bus, "teamserver", key=KEY)
        return TeamServer(self.profile_name, TEAM, key=KEY, clock=self.clock, refbox=link,
                          agents=agents, state=self.state, config=self.config, **self.kw)

    def restart(self):
        """Kill the server (no goodbye) and start a new one on the same database."""
        self.server.agents.close()
        self.server.close()
        self.server = self._server()
        for a in self.agents:       # the clients reconnect to the new server
            a.t = self._client(f"robot{a.number}-again")

    def close(self):
        self.server.agents.close()
        for a in self.agents:
            a.t.close()
        self.server.close()

    def step(self, dt=0.1, n=1):
        for _ in range(n):
            self.clock.advance(dt)
            if self.tcp:        # let loopback frames arrive (bounded, real time)
                self.server.agents.wait(0.002)
            self.server.tick()
            if self.tcp:
                for a in self.agents:
                    a.t.wait(0.002)
            for a in self.agents:
                a.take()
            self.refbox.take()


C0 = {"complexity": 0, "quantity_requested": 1, "quantity_delivered_cyan": 0,
          "quantity_delivered_magenta": 0, "delivery_period_begin": 0, "delivery_period_end": 900,
          "delivery_gate": 1}
PLACES_2016 = {"C-BS": 9, "C-DS": 4, "C-RS1": 2, "C-RS2": 7, "C-CS1": 11, "C-CS2": 6}
RS_2016 = {"C-RS1": ("RING_BLUE", "RING_GREEN"), "C-RS2": ("RING_ORANGE", "RING_YELLOW")}
COSTS_2016 = {"RING_BLUE": 2, "RING_GREEN": 0, "RING_ORANGE": 1, "RING_YELLOW": 0}


def machines_known(ls, places, costs, t=0.0):
    """Our colour, PRODUCTION running at game time ``t``, the machines seen in their
    zones (``places``: machine -> zone), ring ``costs``; ``ls.station_states`` all IDLE."""
    for a in ls.agents:
        a.hello()
        a.status()
    ls.refbox.game_state("PRODUCTION", "RUNNING", t)
    ls.step()
    for name, z in places.items():
        ls.agents[0].observe(name, zone=z, zconf=0.99)
    ls.refbox.rings(costs)
    ls.station_states = dict.fromkeys(places, "IDLE")


def production_setup(ls, orders, t=0.0, states=None):
    """Our colour, PRODUCTION running, known machines, ring costs, idle stations (but
    ``states``: machine -> state), orders."""
    machines_known(ls, PLACES_2016, COSTS_2016, t)
    ls.station_states.update(states or {})
    ls.refbox.machines(ls.station_states, RS_2016)
    bc, cc = ls.refbox.ms.enum("BaseColor"), ls.refbox.ms.enum("CapColor")
    rc = ls.refbox.ms.enum("RingColor")
    full = []
    for o in orders:
        o = dict(C0, **o)
        o.setdefault("base_color", bc.Value("BASE_RED"))
        o.setdefault("cap_color", cc.Value("CAP_BLACK"))
        if "rings" in o:
            o["ring_colors"] = [rc.Value(r) for r in o.pop("rings")]
        full.append(o)
    ls.refbox.orders(full)
    ls.order_msgs = full
    ls.step(n=2)


def task_kinds(agent):
    return [(t.task_id, t.WhichOneof("kind"), getattr(t, t.WhichOneof("kind")).machine
             if t.WhichOneof("kind") not in ("explore_zone", "discard", "go_to") else None)
            for t in agent.tasks()]


FEEDS = ("mount_ring", "mount_cap", "retrieve_cap", "deliver")
SLIDE = "SLIDE"                   # a put onto a ring station's slide (the task's side)


class Stations:
    """The refbox's side of our stations, scripted: a PrepareMachine makes a station
    PREPARED (the BS dispenses at once), a workpiece fed to a PREPARED station is
    processed (DS: delivered, the gate recorded; others: ready at the output), one fed
    to a station not yet prepared waits on its input, and a pickup empties the output.
    States go out in MachineInfo whenever they change."""

    def __init__(self, ls):
        self.ls = ls
        self.states = ls.station_states
        self.instr: dict = {}
        self.waiting: set = set()
        self.deliveries: list = []          # (game time, gate)
        self.waiting_order: dict = {}       # DS -> order of the workpiece on its input
        self.slides: dict = {}              # RS -> additional bases on its slide
        self.seen = 0

    def _send(self):
        self.ls.refbox.machines(self.states, RS_2016,
                                **{rs: {"loaded_with": n} for rs, n in self.slides.items()})

    def slide(self, machine):
        """An additional base reached ``machine``'s slide."""
        self.slides[machine] = self.slides.get(machine, 0) + 1
        self._send()

    def take_prepares(self, gt):
        got = self.ls.refbox.received[self.seen:]
        self.seen = len(self.ls.refbox.received)
        changed = False
        for m in got:
            if m.DESCRIPTOR.name != "PrepareMachine" or self.states.get(m.machine) != "IDLE":
                continue
            self.instr[m.machine] = m
            self.states[m.machine] = "READY-AT-OUTPUT" if m.machine.endswith("BS") else "PREPARED"
            changed = True
            if m.machine in self.waiting:
                self._send()                # every state change goes out
                self.waiting.discard(m.machine)
                self._process(m.machine, gt)
        if changed:
            self._send()

    def _process(self, machine, gt):
        if machine.endswith("DS"):
            gate = self.instr[machine].instruction_ds.gate
            self.deliveries.append((gt, gate))
            self.states[machine] = "IDLE"
            self._count(self.waiting_order.pop(machine, None), gate, gt)
        elif machine[2:4] == "RS":
            cost = COSTS_2016[self.ls.refbox.ms.enum("RingColor").Name(
                self.instr[machine].instruction_rs.ring_color)]
            if self.slides.get(machine, 0) < cost:
                self.states[machine] = "BROKEN"             # the refbox breaks it
            else:
                self.slides[machine] = self.slides.get(machine, 0) - cost
                self.states[machine] = "READY-AT-OUTPUT"
        else:
            self.states[machine] = "READY-AT-OUTPUT"

    def _count(self, order_id, gate, gt):
        """The refbox counts a product for its order at the order's gate in the window."""
        for o in self.ls.order_msgs:
            if o["id"] == order_id and o["delivery_gate"] == gate and \
                    o["delivery_period_begin"] <= gt <= o["delivery_period_end"]:
                o["quantity_delivered_cyan"] += 1
                self.ls.refbox.orders(self.ls.order_msgs)

    def fed(self, machine, gt, task_id=None):
        """A workpiece reached ``machine``'s input (``task_id``: the server's task)."""
        if machine.endswith("DS"):
            t = self.ls.server.kb.tasks.get(task_id)
            p = self.ls.server.kb.products.get(t.product) if t is not None else None
            self.waiting_order[machine] = p.order_id if p is not None else None
        if self.states.get(machine) == "PREPARED":
            self._process(machine, gt)
            self._send()
        else:
            self.waiting.add(machine)

    def taken(self, machine):
        if self.states.get(machine) == "READY-AT-OUTPUT":
            self.states[machine] = "IDLE"
            self._send()


def play(ls, until, *, t0=0.0, dt=0.5, steps=800, fail=None, drop=None, drive=3):
    """Run the game from production time ``t0``: each robot drives to the station of a
    task it gets (``drive`` steps), then reports it done; ``fail(agent, task)`` may
    return a failure (result fields: status, error, holding; ``fed=True``: the feed's workpiece reached
    the station all the same), ``drop(agent, task)`` True makes a feed's
    workpiece fall beside the station (reported done all the same).  True once
    ``until(gt)`` holds.  ``ls.stations`` is the scripted :class:`Stations`."""
    st = ls.stations = getattr(ls, "stations", None) or Stations(ls)
    answered = {a.number: 0 for a in ls.agents}
    doing: dict[int, list] = {a.number: [] for a in ls.agents}
    gt = t0
    pos = ls.server.production.world.positions
    for _ in range(steps):
        gt += dt
        ls.refbox.game_state("PRODUCTION", "RUNNING", gt)
        st.take_prepares(gt)
        for a in ls.agents:
            a.beat()
            tasks = a.tasks()
            new, answered[a.number] = tasks[answered[a.number]:], len(tasks)
            for t in new:
                kind = t.WhichOneof("kind")
                machine = getattr(t, kind).machine if kind not in ("discard", "go_to") else None
                if machine and machine in pos():
                    x, y = pos()[machine]
                    a.pose = (x + 0.3, y, 0.0)
                    into = kind in FEEDS or (kind == "put_workpiece" and t.put_workpiece.side != SLIDE)
                    a.status(waiting_at=machine if into else None)   # docked, waiting
                doing[a.number].append([t, drive])
            for item in list(doing[a.number]):
                item[1] -= 1
                if item[1] > 0:
                    continue
                doing[a.number].remove(item)
                t = item[0]
                kind = t.WhichOneof("kind")
                outcome = fail(a, t) if fail else None
                machine = getattr(t, kind).machine if kind not in ("discard", "go_to") else None
                if outcome:
                    outcome = dict(outcome)
                    if outcome.pop("fed", False) and kind in FEEDS:
                        st.fed(machine, gt, t.task_id)      # failed after it got there
                    a.result(t.task_id, "FAILED", **outcome)
                    continue
                into = kind in FEEDS or (kind == "put_workpiece" and t.put_workpiece.side != SLIDE)
                if into and not (drop and drop(a, t)):
                    st.fed(machine, gt, t.task_id)
                elif kind == "put_workpiece" and t.put_workpiece.side == SLIDE and not (
                        drop and drop(a, t)):
                    st.slide(machine)
                elif kind == "get_workpiece":
                    st.taken(machine)
                a.result(t.task_id, holding=kind == "get_workpiece")
        ls.step(dt=dt)
        if until(gt):
            return True
    return False


def abandon_all_products(server) -> None:
    """Every product the server planned given up (its open tasks cancelled), as after its orders ended."""
    kb = server.kb
    for p in list(kb.products.values()):
        server.production.products.cancel_open(p)
        p.state = "ABANDONED"
        kb.save_product(p)


def run_tasks(ls, until, fail=None, steps=400):
    """Complete every task the agents get; ``fail(agent, task)`` may return a failure."""
    answered = {a.number: 0 for a in ls.agents}     # a re-sent task is answered again
    for _ in range(steps):
        for a in ls.agents:
            a.beat()
            tasks = a.tasks()
            new, answered[a.number] = tasks[answered[a.number]:], len(tasks)
            for t in new:
                outcome = fail(a, t) if fail else None
                if outcome:
                    a.result(t.task_id, "FAILED", **outcome)
                else:
                    a.result(t.task_id, holding=t.WhichOneof("kind") == "get_workpiece")
        ls.step(dt=0.5)
        if until():
            return True
    return False
