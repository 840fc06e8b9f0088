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

from refbox_scenarios import KEY, TEAM, scenarios  # a sibling: the scripts run from benchmarks/

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
