"""Part 2 of benchmarks/refbox_rules.py: the scenarios played in one named game of a real
refbox and of the simulated refbox, side by side (see that script's docstring)."""
from __future__ import annotations

import re
import time

TEAM, KEY = "Carologistics", "randomkey"      # the team the real refbox is configured with
GIVING_RE = re.compile(r"Giving (-?\d+) points to team CYAN: (.*) \(PRODUCTION @")


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
