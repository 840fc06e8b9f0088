"""Manual check: the simulated refbox's 2025 rules against a REAL refbox binary.

Not part of the suite (the refbox cannot be shipped with the project); run it by
hand against a refbox you built yourself (docs/league.md)::

    LD_LIBRARY_PATH=... python benchmarks/refbox_rules.py --refbox /path/to/bin/refbox \\
        [--games 30] [--speedup 8] [--json FILE]

Part 1, what the real refbox draws (``--games`` refbox starts without team
names, so it prints its game to stdout): the cyan field its solver placed,
the order schedule, ring costs and down periods.  Every real field must keep
every constraint of :mod:`backends.sim.placing2025`, every schedule the
constraints the simulated refbox's generator keeps
(:func:`schedule_problems`), every down period its range; then the same
numbers of as many of our own draws are printed beside the real ones.

Part 2, scenarios in one named game (mockup stations, two ring stations on
MQTT with no machine behind them, game time ``--speedup`` times the clock,
exploration time 10 s): a prepare without instruction; an RS prepared with a
free colour and never fed (BROKEN after 20 s); an RS prepared without its
additional bases; a DS prepared for an order whose window has not opened;
bases on a slide and a retrieved cap taken back when the machine breaks;
storage costs and a relocation; WAIT-IDLE after a delivery; a late delivery.
For each it prints what the real refbox did (MachineInfo states in game
seconds, points) beside what the simulated refbox does in the same scenario,
and exits 0 only when they agree.
"""
from __future__ import annotations

import argparse
import json
import os
import random
import re
import subprocess
import sys
import tempfile
import threading
import time
from statistics import mean

TEAM, KEY = "Carologistics", "randomkey"
ORDER_RE = re.compile(r"Order (\d+): C(\d) \((\w+)\|([\w ]*)\|(\w+)\) from (\d+):(\d+) to "
                      r"(\d+):(\d+) \(@(\d+):(\d+) ~(\d+)s\) D(\d)")
FIELD_RE = re.compile(r"C-(\w+): C_Z(\d)(\d) with (\d+)")
DOWN_RE = re.compile(r"C-(\w+) down from (\d+):(\d+) to (\d+):(\d+)")
RING_RE = re.compile(r"Ring color (\w+) requires (\d) additional bases")


def config(*, team: bool, exploration_time: int = 180, speedup: float = 1.0,
           mqtt: dict[str, int] | None = None, down: bool = True) -> str:
    lines = ["%YAML 1.2", "%TAG ! tag:fawkesrobotics.org,cfg/", "---", "# rll-bt rules check", "---",
             "llsfrb:", "  clips:", "    debug: false", "    debug-level: 0",
             "  game:", f"    exploration-time: {exploration_time}",
             f"    random-machine-down-times: {'true' if down else 'false'}"]
    if team:
        lines += [f"    teams: [{TEAM}]", "    crypto-keys:", f"      {TEAM}: {KEY}"]
    if speedup != 1.0:
        lines += ["  simulation:", "    enable: true", f"    speedup: {speedup}",
                  "    time-sync:", "      enable: false", "      estimate-time: false"]
    if mqtt:
        lines += ["  mps:", "    stations:"]
        for name, port in mqtt.items():
            lines += [f"      {name}:", "        active: true", "        type: RS",
                      "        connection: mqtt", "        host: 127.0.0.1",
                      f"        port: !tcp-port {port}"]
    return "\n".join(lines) + "\n"


class Refbox:
    """One run of the refbox binary in a scratch directory; stdout collected."""

    def __init__(self, binary: str, cfg: str):
        self.dir = tempfile.mkdtemp(prefix="rll-bt-rules-")
        path = os.path.join(self.dir, "check.yaml")
        with open(path, "w") as f:
            f.write(cfg)
        self.out_path = os.path.join(self.dir, "out.log")
        self._out = open(self.out_path, "w")  # noqa: SIM115 (closed in stop)
        self.proc = subprocess.Popen([binary, "--cfg-custom", path], cwd=self.dir,
                                     stdout=self._out, stderr=subprocess.STDOUT)

    def text(self) -> str:
        with open(self.out_path, errors="replace") as f:
            return f.read()

    def wait_for(self, text: str, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.text():
                return True
            if self.proc.poll() is not None:
                raise RuntimeError(f"the refbox ended ({self.proc.returncode}): {self.text()[-500:]}")
            time.sleep(0.2)
        return False

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)
        self._out.close()
        for name in os.listdir(self.dir):              # the debug log can grow large
            if name.startswith("refbox-debug"):
                os.remove(os.path.join(self.dir, name))


class Link:
    """Control over TCP 4444; the team channel (cyan) and public channel as a robot."""

    def __init__(self, team: bool):
        from rll_bt import msgs
        from rll_bt.comm import MessageRegistry, StreamClient, UdpPeer
        self.ms = msgs.message_set("rcll2025")
        reg = MessageRegistry.from_message_set(self.ms)
        self.ctl = StreamClient("127.0.0.1", 4444, registry=reg, channel="control")
        self.pub = UdpPeer("127.0.0.1", 4445, 4444, registry=reg, channel="public")
        self.peer = UdpPeer("127.0.0.1", 4446, 4441, registry=reg, channel="team",
                            key=KEY) if team else None
        self._gt = (0.0, time.monotonic())     # game time of the last GameState, when
        self.speedup = 1.0
        self._phase = None
        self.points = 0
        self.states: dict[str, list[tuple[float, str]]] = {}
        self.orders: dict[int, object] = {}
        self.attention: list[str] = []
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._listen, daemon=True)
        self._t.start()

    def _listen(self):
        while not self._stop.is_set():
            self.pub.wait(0.05)
            recs = list(self.pub.receive()) + (list(self.peer.receive()) if self.peer else [])
            self.ctl.wait(0.0)
            recs += list(self.ctl.receive())
            for r in recs:
                name = r.type_name.rsplit(".", 1)[-1]
                if name == "GameState":
                    gt = r.msg.game_time.sec + r.msg.game_time.nsec / 1e9
                    running = r.msg.state == self.ms.enum("GameState.State").Value("RUNNING")
                    if r.msg.phase != self._phase:
                        self._phase = r.msg.phase
                        self.states.clear()           # a new phase: game time restarts
                    self._gt = (gt, time.monotonic()) if running else (gt, None)
                    self.points = r.msg.points_cyan
                elif name == "MachineInfo":
                    for m in r.msg.machines:
                        seq = self.states.setdefault(m.name, [])
                        if not seq or seq[-1][1] != m.state:
                            seq.append((self.game_time, m.state))
                elif name == "OrderInfo":
                    for o in r.msg.orders:
                        self.orders[o.id] = o
                elif name == "AttentionMessage":
                    self.attention.append(r.msg.message)

    @property
    def game_time(self) -> float:
        """Game seconds now: the last GameState's (1 Hz) plus the clock since, times the
        game's speed-up."""
        gt, at = self._gt
        return gt if at is None else gt + (time.monotonic() - at) * self.speedup

    def control(self, name, **fields):
        assert self.ctl.wait_connected(20), "refbox TCP 4444 not reachable"
        assert self.ctl.send(self.ms.get(name)(**fields)), f"{name} not sent"

    def send(self, name, **fields):
        self.peer.send(self.ms.get(name)(**fields))

    def wait_game(self, until: float, timeout: float = 300.0) -> None:
        deadline = time.monotonic() + timeout
        while self.game_time < until and time.monotonic() < deadline:
            time.sleep(0.05)

    def seen(self, machine: str, since: float) -> list[tuple[float, str]]:
        return [(round(t - since, 1), s) for t, s in self.states.get(machine, []) if t >= since]

    def close(self):
        self._stop.set()
        self._t.join(2)
        for c in (self.pub, self.peer, self.ctl):
            if c is not None:
                c.close()


def mmss(m: str, s: str) -> int:
    return int(m) * 60 + int(s)


# -- part 1: what the refbox draws --------------------------------------------------------

def parse_game(text: str) -> dict:
    field = {t: (int(x), int(y), int(a)) for t, x, y, a in FIELD_RE.findall(text)}
    orders = []
    for m in ORDER_RE.findall(text):
        oid, cx, base, rings, cap = int(m[0]), int(m[1]), m[2], m[3].split(), m[4]
        begin, end, act = mmss(m[5], m[6]), mmss(m[7], m[8]), mmss(m[9], m[10])
        orders.append({"id": oid, "complexity": cx, "base": base, "rings": rings, "cap": cap,
                       "begin": begin, "end": end, "activate_at": act, "gate": int(m[12])})
    down = [(t, mmss(a, b), mmss(c, d)) for t, a, b, c, d in DOWN_RE.findall(text)]
    costs = {c: int(n) for c, n in RING_RE.findall(text)}
    return {"field": field, "orders": orders, "down": down, "costs": costs}


def schedule_problems(orders: list[dict], costs: dict[str, int]) -> list[str]:
    """What in a 2025 schedule breaks the constraints our generator keeps."""
    o = {x["id"]: x for x in orders}
    bad = []
    if sorted(o) != list(range(1, 12)):
        return [f"order ids {sorted(o)}"]
    if o[1]["complexity"] not in (0, 1) or o[2]["complexity"] not in (2, 3):
        bad.append("standing complexities")
    mid = [o[i]["complexity"] for i in range(3, 11)]
    if sum(c < 2 for c in mid) != 4:
        bad.append(f"complexities of #3-#10: {mid}")
    free = {c for c, n in costs.items() if n == 0}
    firsts = set()
    for x in orders:
        r = x["rings"]
        if any(a == b for a, b in zip(r, r[1:])):
            bad.append(f"#{x['id']} consecutive rings equal")
        if x["id"] <= 2 and r and r[0] not in free:
            bad.append(f"#{x['id']} standing first ring not free")
        if r:
            if (x["base"], r[0]) in firsts:
                bad.append(f"#{x['id']} base + first ring not unique")
            firsts.add((x["base"], r[0]))
        if 3 <= x["id"] <= 10:
            if not 180 <= x["activate_at"] <= 960:
                bad.append(f"#{x['id']} announced at {x['activate_at']}")
            lo, hi = (90, 180) if x["complexity"] < 2 else (150, 210)
            if not lo <= x["end"] - x["begin"] <= hi or x["end"] > 1200:
                bad.append(f"#{x['id']} window {x['begin']}-{x['end']}")
    return bad


def ours(n: int) -> list[dict]:
    """``n`` draws of our own generator in the same shape as :func:`parse_game`'s."""
    from backends.sim.placing2025 import solve
    from backends.sim.refbox import Rules2025, Timing
    from backends.sim.refbox.orders2025 import schedule_2025
    from rll_bt.rules import profile
    p = profile("rcll2025")
    rng, timing = random.Random(17), Timing.from_profile(p)
    out = []
    for _ in range(n):
        _rs, costs = p.ring_setup(rng)
        orders = [{"id": o.id, "complexity": o.complexity, "base": o.base, "rings": list(o.rings),
                   "cap": o.cap, "begin": o.begin, "end": o.end, "activate_at": o.activate_at,
                   "gate": o.gate} for o in schedule_2025(p, rng, timing, costs)]
        down = [(m[2:], a, b) for m, (a, b) in Rules2025().down_periods(p, rng, timing).items()
                if m.startswith("C-")]
        out.append({"field": solve(rng), "orders": orders, "down": down, "costs": costs})
    return out


def stats(games: list[dict]) -> dict:
    def neighbours(f):
        zs = [(x, y) for x, y, _ in f.values()]
        return any(abs(a[0] - b[0]) <= 1 and abs(a[1] - b[1]) <= 1
                   for i, a in enumerate(zs) for b in zs[i + 1:])
    mid = [x for g in games for x in g["orders"] if 3 <= x["id"] <= 10]
    c3 = [x for g in games for x in g["orders"] if x["complexity"] == 3]
    return {
        "fields with neighbouring machines": mean(neighbours(g["field"]) for g in games),
        "fields using column 1": mean(any(x == 1 for x, _, _ in g["field"].values()) for g in games),
        "mean window C0/C1 (s)": mean(x["end"] - x["begin"] for x in mid if x["complexity"] < 2),
        "mean window C2/C3 (s)": mean(x["end"] - x["begin"] for x in mid if x["complexity"] >= 2),
        "announced at 180 s": mean(x["activate_at"] == 180 for x in mid),
        "mean announcement #3-#10 (s)": mean(x["activate_at"] for x in mid),
        "C3 ring 3 = ring 1": mean(x["rings"][2] == x["rings"][0] for x in c3) if c3 else None,
        "mean down length (s)": mean(b - a for g in games for _, a, b in g["down"]),
        "earliest down start (s)": min(a for g in games for _, a, _ in g["down"]),
    }


def part1(binary: str, n: int) -> tuple[bool, dict]:
    """``n`` games of one refbox process: the first as it starts, then each after a
    RandomizeField (the refbox seeds its generator once, from the clock, so fresh
    processes started close together draw the same orders; a reset draws anew)."""
    from backends.sim.placing2025 import valid
    real = []
    rb = Refbox(binary, config(team=False))
    link = None
    try:
        if not rb.wait_for("Creating local communication peer", 30):
            raise RuntimeError("the refbox did not come up")
        link = Link(team=False)
        link.control("SetGamePhase", phase="SETUP")
        time.sleep(0.5)
        link.control("SetGameState", state="RUNNING")
        for i in range(n):
            mark = len(rb.text())
            deadline = time.monotonic() + 120
            while "machine generation is finished" not in rb.text()[mark:] or \
                    "Order 11:" not in rb.text()[mark:]:
                if time.monotonic() > deadline:
                    raise RuntimeError("no field generated")
                time.sleep(0.2)
            link.control("SetGamePhase", phase="PRODUCTION")
            deadline = time.monotonic() + 20
            while "down from" not in rb.text()[mark:] and time.monotonic() < deadline:
                time.sleep(0.2)
            time.sleep(0.3)
            real.append(parse_game(rb.text()[mark:]))
            print(f"  real game {i + 1}/{n}: {len(real[-1]['orders'])} orders, "
                  f"{len(real[-1]['field'])} machines", file=sys.stderr)
            link.control("SetGamePhase", phase="SETUP")       # back in SETUP: WAIT_START
            time.sleep(0.5)
            link.control("RandomizeField")
            time.sleep(0.5)
            link.control("SetGameState", state="RUNNING")     # the solver is checked by game time
    finally:
        if link:
            link.close()
        rb.stop()
    ok = True
    for i, g in enumerate(real):
        problems = valid(g["field"]) + schedule_problems(g["orders"], g["costs"])
        problems += [f"down {t} {a}-{b}" for t, a, b in g["down"]
                     if not (30 <= b - a <= 60 and a >= 180 and b <= 1200)]
        if problems:
            ok = False
            print(f"real game {i + 1}: {problems} {g['field']}")
    distinct = len({json.dumps(g["orders"], sort_keys=True) for g in real})
    print(f"{distinct} distinct schedules, "
          f"{len({json.dumps(g['field'], sort_keys=True) for g in real})} distinct fields")
    sim = ours(max(n, 200))
    rs, ss = stats(real), stats(sim)
    print(f"\n{'what (2025)':34} {'real refbox':>12} {'simulated':>10}   ({n} real, {len(sim)} simulated)")
    def fmt(v):
        return "-" if v is None else f"{v:.2f}" if isinstance(v, float) else str(v)
    for k in rs:
        print(f"{k:34} {fmt(rs[k]):>12} {fmt(ss[k]):>10}")
    return ok, {"real": real, "stats_real": rs, "stats_sim": ss}


# -- part 2: scenarios -------------------------------------------------------------------

GIVING_RE = re.compile(r"Giving (-?\d+) points to team CYAN: (.*) \(PRODUCTION @")


def part2(binary: str, speedup: float) -> tuple[bool, list]:
    from backends.sim.mps import Broker
    broker = Broker("amqtt")
    rb = Refbox(binary, config(team=True, exploration_time=10, speedup=speedup, down=False,
                               mqtt={"C-RS1": broker.port, "C-RS2": broker.port}))
    link = None
    rows = []
    try:
        if not rb.wait_for("Creating local communication peer", 30):
            raise RuntimeError("the refbox did not come up")
        link = Link(team=True)
        link.speedup = speedup
        for name, fields in (("SetTeamName", {"team_name": TEAM, "team_color": "CYAN"}),
                             ("SetGamePhase", {"phase": "SETUP"}),
                             ("SetGameState", {"state": "RUNNING"})):
            link.control(name, **fields)
            time.sleep(0.5)
        if not rb.wait_for("machine generation is finished", 120):
            raise RuntimeError("no field generated")
        link.control("SetGamePhase", phase="PRODUCTION")
        link.wait_game(15)                         # ground truth out: every machine usable
        deadline = time.monotonic() + 20
        while "C-BS" not in link.states and time.monotonic() < deadline:
            time.sleep(0.1)                        # the team channel works both ways
        costs = {c: int(k) for c, k in RING_RE.findall(rb.text())}
        colors = {m: re.search(rf"RS {m} has colors \((\w+) (\w+)\)", rb.text()).groups()
                  for m in ("C-RS1", "C-RS2")}
        rows = scenarios(link, rb, costs, colors)
    finally:
        if link:
            link.close()
        rb.stop()
        broker.stop()
    ok = all(r[1] for r in rows)
    print(f"\n{'scenario (2025)':52} {'same':5} real refbox | simulated refbox")
    for name, same, real, sim in rows:
        print(f"{name:52} {'yes' if same else 'NO':5} {real} | {sim}")
    return ok, rows


def prep(link, machine, **instr):
    link.send("PrepareMachine", team_color="CYAN", machine=machine, **instr)


def scenarios(link, rb, costs, colors) -> list:
    from backends.sim.refbox import (
        CSInstruction,
        DSInstruction,
        RefboxGame,
        RSInstruction,
        SSInstruction,
        Timing,
        Workpiece,
    )
    from rll_bt.clock import SimClock
    from rll_bt.rules import profile

    def sim_game():
        clock = SimClock()
        t = Timing.from_profile(profile("rcll2025"), setup=1, exploration=0)
        g = RefboxGame("rcll2025", clock, seed=3, team_cyan=TEAM, timing=t)
        g.ring_costs = dict(costs)
        g.start()
        g.set_phase("PRODUCTION")

        def run(s):
            for _ in range(int(round(s * 4))):
                clock.advance(0.25)
                g.tick()
        return g, run

    def states(g, m, since=0.0):
        return [(round(e.game_time - since, 1), e.data["state"]) for e in g.events
                if e.kind == "machine" and e.machine == m and e.game_time >= since]

    def awards_since(mark):
        return [int(p) for p, _ in GIVING_RE.findall(rb.text()[mark:])]

    def sim_awards(g, n=0):
        return [e.points for e in g.ledger.entries[n:] if e.team == "CYAN"]

    def until_idle(machine, limit=120.0):
        end = link.game_time + limit
        while link.game_time < end:
            seq = link.states.get(machine, [])
            if seq and seq[-1][1] == "IDLE":
                return
            time.sleep(0.05)

    rows = []
    # 1. a prepare without an instruction (sent until it arrives: the refbox drops the first
    #    messages on a fresh team channel)
    for _ in range(10):
        t0 = link.game_time
        prep(link, "C-BS")
        link.wait_game(t0 + 2 * link.speedup)
        real = [s for _, s in link.seen("C-BS", t0)]
        if real:
            break
    g, run = sim_game()
    g.prepare("CYAN", "C-BS", None, "CYAN")
    sim = [s for _, s in states(g, "C-BS")][1:]
    rows.append(("prepare without instruction breaks", real[:1] == sim[:1] == ["BROKEN"], real, sim))

    free = [(m, c) for m, cs in colors.items() for c in cs if costs.get(c) == 0]
    costly = [(m, c) for m, cs in colors.items() for c in cs if costs.get(c, 0) > 0]

    # 2. an RS prepared with a free colour and never fed: BROKEN 20 s later
    used = set()
    if free:
        rs, color = free[0]
        used.add(rs)
        t0 = link.game_time
        prep(link, rs, instruction_rs={"ring_color": color})
        link.wait_game(t0 + 25)
        real = link.seen(rs, t0)
        g, run = sim_game()
        g.prepare("CYAN", rs, RSInstruction(color), "CYAN")
        run(25)
        sim = states(g, rs)[1:]
        same = [s for _, s in real] == [s for _, s in sim] == ["PREPARED", "BROKEN"] and \
            abs(real[1][0] - sim[1][0]) <= 1.5
        rows.append(("RS prepared, never fed: BROKEN after 20 s", same, real, sim))

    # 3. an RS prepared without its additional bases: BROKEN at once
    rest = [(m, c) for m, c in costly if m not in used] or costly
    if rest:
        rs, color = rest[0]
        until_idle(rs)
        t0, mark = link.game_time, len(rb.text())
        prep(link, rs, instruction_rs={"ring_color": color})
        link.wait_game(t0 + 3)
        real = link.seen(rs, t0)
        g, run = sim_game()
        g.prepare("CYAN", rs, RSInstruction(color), "CYAN")
        sim = states(g, rs)[1:]
        rows.append((f"RS prepared without its {costs[color]} bases: BROKEN", bool(real) and
                     real[-1][1] == "BROKEN" and sim[-1][1] == "BROKEN"
                     and abs(real[-1][0] - sim[-1][0]) <= 2.5, real, sim))

    # 4. a DS prepared for an order whose window has not opened: BROKEN after 20 s
    future = []
    while not future and link.game_time < 600:
        future = [o for o in link.orders.values()
                  if o.delivery_period_begin > link.game_time + 30]
        if not future:
            link.wait_game(link.game_time + 10)
    if future:
        o = future[0]
        until_idle("C-DS")
        t0 = link.game_time
        prep(link, "C-DS", instruction_ds={"order_id": o.id})
        link.wait_game(t0 + 25)
        real = link.seen("C-DS", t0)
        g, run = sim_game()
        so = g.order(3)
        so.active, so.begin, so.end = True, 500, 700
        g.prepare("CYAN", "C-DS", DSInstruction(order_id=3), "CYAN")
        run(25)
        sim = states(g, "C-DS")[1:]
        same = [s for _, s in real] == [s for _, s in sim] == ["PREPARED", "BROKEN"] and \
            abs(real[1][0] - sim[1][0]) <= 1.5
        rows.append(("DS before its order's window: BROKEN after 20 s", same, real, sim))

    # 5. bases on a slide and a retrieved cap are taken back when the machine breaks
    rs = "C-RS2"
    until_idle(rs)
    mark = len(rb.text())
    for _ in range(2):
        link.control("MachineAddBase", machine_name=rs)
        time.sleep(0.3)
    time.sleep(1.0)
    link.send("ResetMachine", team_color="CYAN", machine=rs)
    time.sleep(1.5)
    real = awards_since(mark)
    g, run = sim_game()
    for _ in range(2):
        g.stations[rs].load_slide()
    g.reset_machine("CYAN", rs, "CYAN")
    sim = sim_awards(g)
    rows.append(("2 slide bases, then the RS breaks: points", real == sim, real, sim))

    until_idle("C-CS1")
    t0, mark = link.game_time, len(rb.text())
    prep(link, "C-CS1", instruction_cs={"operation": "RETRIEVE_CAP"})
    link.wait_game(t0 + 26)
    link.send("ResetMachine", team_color="CYAN", machine="C-CS1")
    time.sleep(1.5)
    real = awards_since(mark)
    g, run = sim_game()
    g.prepare("CYAN", "C-CS1", CSInstruction("RETRIEVE_CAP"), "CYAN")
    g.stations["C-CS1"].feed(Workpiece("BASE_RED", (), "CAP_GREY"))
    run(26)
    g.reset_machine("CYAN", "C-CS1", "CYAN")
    sim = sim_awards(g)
    rows.append(("cap retrieved, then the CS breaks: points", real == sim, real, sim))

    # 6. storage: retrieve a pre-stored C0, store in front of another, relocate to retrieve
    ops = ({"operation": "RETRIEVE", "shelf": 0, "slot": 1},
           {"operation": "STORE", "shelf": 1, "slot": 0},
           {"operation": "RETRIEVE", "shelf": 1, "slot": 1})
    until_idle("C-SS")
    t0, mark = link.game_time, len(rb.text())
    for instr in ops:
        ts = link.game_time
        prep(link, "C-SS", instruction_ss=instr)
        link.wait_game(ts + 2)
        until_idle("C-SS")
    real = (awards_since(mark), [s for _, s in link.seen("C-SS", t0)])
    g, run = sim_game()
    ss = g.stations["C-SS"]
    for instr in ops:
        g.prepare("CYAN", "C-SS", SSInstruction(**instr), "CYAN")
        if instr["operation"] == "STORE":
            ss.feed(Workpiece("BASE_RED"))
        for _ in range(200):
            run(0.5)
            if ss.state == "READY-AT-OUTPUT":
                ss.on_take("output", g.world.remove_workpiece("C-SS", "output"))
            if ss.state == "IDLE":
                break
    sim = (sim_awards(g), [s for _, s in states(g, "C-SS")][1:])
    real = ([p for p in real[0] if p], real[1])          # the relocation's 0 is logged too
    rows.append(("storage: retrieve, store, relocate + retrieve: points", real[0] == sim[0],
                 real, sim))

    # 7. WAIT-IDLE after a delivery (order 0: consume only)
    until_idle("C-DS")
    t0 = link.game_time
    prep(link, "C-DS", instruction_ds={"order_id": 0})
    link.wait_game(t0 + 16)
    real = link.seen("C-DS", t0)
    g, run = sim_game()
    g.prepare("CYAN", "C-DS", DSInstruction(order_id=0), "CYAN")
    g.stations["C-DS"].feed(Workpiece("BASE_RED"))
    run(16)
    sim = states(g, "C-DS")[1:]
    rsq = {s: t for t, s in real}
    ssq = {s: t for t, s in sim}
    same = all(s in rsq for s in ("PROCESSED", "WAIT-IDLE", "IDLE")) and \
        abs((rsq["IDLE"] - rsq["WAIT-IDLE"]) - (ssq["IDLE"] - ssq["WAIT-IDLE"])) <= 1.5
    rows.append(("a delivery: WAIT-IDLE for 5 s, then IDLE", same, real, sim))

    # 8. a late delivery: the graded deduction
    late = None
    while late is None and link.game_time < 1100:
        late = next((o for o in link.orders.values()
                     if o.delivery_period_end + 20 < link.game_time and o.complexity == 0
                     and not o.quantity_delivered_cyan), None)
        if late is None:
            link.wait_game(link.game_time + 10)
    if late is not None:
        until_idle("C-DS")
        t0, mark = link.game_time, len(rb.text())
        prep(link, "C-DS", instruction_ds={"order_id": late.id})
        link.wait_game(t0 + 40)                   # delivered, WAIT-IDLE, confirmed
        at = next((float(t) for t in re.findall(r"Delivered item for order \(PRODUCTION @ "
                                                 r"([\d.]+)", rb.text()[mark:])), t0 + 4)
        real = awards_since(mark)
        g, run = sim_game()
        so = g.order(3)
        so.complexity, so.rings, so.active, so.competitive = 0, (), True, late.competitive
        so.begin, so.end = late.delivery_period_begin, late.delivery_period_end
        so.base = {1: "BASE_RED", 2: "BASE_BLACK", 3: "BASE_SILVER"}[late.base_color]
        so.cap = {1: "CAP_BLACK", 2: "CAP_GREY"}[late.cap_color]
        res = g.rules.judge_delivery(g.profile, g.orders, "CYAN", Workpiece(so.base, (), so.cap),
                                     0, at, g.ring_costs, 3)
        sim = [p for p, _ in res.awards]
        full = g.profile.scoring.delivery_by_complexity[0]
        rows.append((f"C0 delivered {at - late.delivery_period_end:.0f} s late (window "
                     f"{late.delivery_period_end - late.delivery_period_begin} s): points",
                     sum(real) == sum(sim) and min(real) == sim[0] - full, real, sim))

    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refbox", required=True, help="path of the refbox binary (bin/refbox)")
    ap.add_argument("--games", type=int, default=20, help="refbox starts for part 1 (default 20)")
    ap.add_argument("--speedup", type=float, default=8.0, help="game time per clock second, part 2")
    ap.add_argument("--only", choices=("draws", "scenarios"), help="run one part only")
    ap.add_argument("--json", help="write what was seen here")
    args = ap.parse_args(argv)
    ok, out = True, {}
    if args.only != "scenarios":
        good, out["draws"] = part1(args.refbox, args.games)
        ok &= good
    if args.only != "draws":
        good, out["scenarios"] = part2(args.refbox, args.speedup)
        ok &= good
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1, default=str)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
