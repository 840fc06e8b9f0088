"""``rll-bt sim --external-team``: an AgentTask team server that is not rll-bt's
(tests/support/league_server.py, written from the league's field tables)
drives rll-bt's simulated robots in the PyBullet world, on the wall clock,
against rll-bt's refbox: exploration moves, a whole C0 with the prepares it
sends the refbox itself (each feed's station prepared once the robot waits
docked at it, as the real rules want), tasks that cannot be done answered with the
league's error codes, beacons with the current and finished tasks."""
from __future__ import annotations

import math

import pytest

from games.league_sim import BROADCAST, ExternalGame, ExternalTeam
from rll_bt.comm import Layout, PeerPorts, free_ports
from tests.support.league_server import BASE, L, LeagueServer

pytestmark = pytest.mark.slow  # whole games on the wall clock: `make test-fast` leaves them out

TEAM, KEY = "Leaguers", "league-key"
PRODUCTION = 30          # GameState.phase
CS_OP = {"RETRIEVE_CAP": 1, "MOUNT_CAP": 2}
CS_OF_CAP = {"CAP_GREY": "C-CS1", "CAP_BLACK": "C-CS2"}     # the refbox's default shelves
SPEED = 3.0     # game seconds per wall second: the games run faster than real time, as the league's simulator can


def make_game(robots: int, exploration: float, seed: int = 1):
    p = free_ports(6)
    layout = Layout("test", public=PeerPorts(send=p[0], recv=p[1]), cyan=PeerPorts(send=p[2], recv=p[3]),
                    magenta=PeerPorts(send=p[4], recv=p[5]), stream=-1)
    pub, cyan = layout.robot("public"), layout.robot("cyan")
    server = LeagueServer(0, (BROADCAST, pub.send, pub.recv, cyan.send, cyan.recv), TEAM, KEY)
    game = ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", server.port), TEAM, KEY, robots=robots)],
                        profile="rcll2025", seed=seed, layout=layout,
                        phases={"setup": 3.0, "exploration": exploration, "production": 1200.0}, speed=SPEED)
    game.hooks.append(lambda g: server.poll())
    assert game.connect(timeout=30.0), "the robots did not connect to the team server"
    return game, server


def finish(game, server, task_id, limit=180.0):
    assert game.run_until(lambda g: server.result(task_id) is not None, limit), f"task {task_id} unanswered"
    return server.result(task_id)


def zone_centre(zone: int) -> tuple[float, float]:
    """The centre of a 2025 zone (C_Zxy = xy, M_Zxy = 1000 + xy; 1 m squares, magenta at x < 0)."""
    x, y = (zone % 1000) // 10, zone % 10
    return ((x - 0.5) * (-1 if zone >= 1000 else 1), y - 0.5)


def docked(server, robot, task_id, zone, still=0.02) -> bool:
    """Robot ``robot`` runs ``task_id`` near the station in ``zone`` and its last
    three beacons (2 s) show it standing still: docked, waiting for the prepare."""
    beacons = [b for b in server.robot(robot).beacons if b.HasField("task") and b.task.task_id == task_id]
    if len(beacons) < 4:
        return False
    last = beacons[-3:]
    cx, cy = zone_centre(zone)
    near = math.hypot(last[-1].pose.x - cx, last[-1].pose.y - cy) < 1.6
    return near and all(math.hypot(b.pose.x - last[0].pose.x, b.pose.y - last[0].pose.y) < still
                        and abs(b.pose.ori - last[0].pose.ori) < 0.02 for b in last[1:])


def in_production(game, server):
    return game.run_until(lambda g: server.phase() is not None and server.phase()[0] == PRODUCTION, 30.0)


@pytest.mark.timeout(900)
def test_a_league_team_server_explores_and_gets_the_leagues_error_codes():
    game, server = make_game(robots=2, exploration=600.0)
    try:
        assert {r.number for r in server.robots} == {1, 2}
        assert in_production(game, server)
        # exploration moves: a Move to a zone and an ExploreWaypoint, two robots at once
        move = server.task(1, move={"waypoint": "C_Z43"})
        look = server.task(2, explore_machine={"machine_id": "C-BS", "machine_point": "output",
                                               "waypoint": "C_Z63"})
        assert game.run_until(lambda g: any(b.HasField("task") and b.task.task_id == move
                                            for b in server.robot(1).beacons), 10.0)
        current = [b.task for b in server.robot(1).beacons if b.HasField("task")][-1]
        assert current.move.waypoint == "C_Z43" and not current.HasField("successful")   # field 9
        for tid in (move, look):
            res = finish(game, server, tid)
            assert res.successful and not res.canceled and not res.HasField("error_code"), res
        assert res.explore_machine.waypoint == "C_Z63"            # the result is the task, echoed
        game.run_until(lambda g: False, 2.5)
        last = server.robot(1).beacons[-1]
        assert not last.HasField("task") and (move, True) in [(f.TaskId, f.successful) for f in last.finished_tasks]
        # tasks that cannot be done: refused before they run, or failed when tried
        cases = {
            server.task(1, retrieve={"machine_id": "C-XX", "machine_point": "output"}): "INVALID_TARGET",
            server.task(1, buffer={"machine_id": "C-RS1", "shelf_number": 1}): "INVALID_TARGET",
            server.task(1, move={"waypoint": "C_Z99"}): "INVALID_TARGET",
            server.task(7, via=1, move={"waypoint": "C_Z43"}): "WRONG_ROBOT",   # to robot 7 on robot 1's link
            server.task(1, deliver={"machine_id": "C-DS", "machine_point": "input"}): "NO_WORKPIECE_IN_GRIPPER",
            server.task(2, move={"waypoint": "C-RS2", "machine_point": "input"}): "MPS_NOT_FOUND",   # not found yet
        }
        for tid, code in cases.items():
            res = finish(game, server, tid)
            assert not res.successful and server.error(tid) == code, (tid, code, res)
        # cancel: the robot stops and says so
        far = server.task(2, move={"waypoint": "M_Z52"})
        game.run_until(lambda g: False, 3.0)
        cancel = L.AgentTask(team_color=0, task_id=far, robot_id=2, cancel_task=True)
        server.send_robot(2, cancel)
        res = finish(game, server, far, limit=10.0)
        assert res.canceled and not res.successful
        # the same task id again is not run again: its result comes back
        again = L.AgentTask(team_color=0, task_id=move, robot_id=1)
        again.move.waypoint = "M_Z52"
        server.send_robot(1, again)
        server.results.pop(move)
        assert finish(game, server, move, limit=10.0).successful
        assert game.agents[("CYAN", 1)].run is None
    finally:
        game.close()
        server.close()


@pytest.mark.timeout(1200)
def test_a_league_team_server_makes_a_c0_with_the_prepares_it_sends():
    # seed 8: the standing C0 (active from the start, grey cap: C-CS1) with every station it needs on our half
    game, server = make_game(robots=1, exploration=20.0, seed=8)
    try:
        assert in_production(game, server)
        # once the exploration time is over the refbox reveals the stations (and the robots read it)
        assert game.run_until(lambda g: server.phase()[1] > 21.0 and len(server.machines) >= 7, 60.0)
        assert game.run_until(lambda g: any(o.complexity == 0 for o in server.orders.values()), 60.0)

        def cs_of(o):
            return CS_OF_CAP["CAP_GREY" if o.cap_color == 2 else "CAP_BLACK"]
        # a C0, earliest first, preferring one whose cap station stands on our half (the 2025
        # field may put one of ours on the other half, in a corner the robot's shelf approach
        # cannot always manage: "move relative blocked ... something is in the way")
        c0 = sorted((o for o in server.orders.values() if o.complexity == 0),
                    key=lambda o: (server.machines[cs_of(o)].zone >= 1000, o.delivery_period_begin))
        order = c0[0]
        base = {v: k for k, v in BASE.items()}[order.base_color]
        cs = cs_of(order)

        def state(machine, *states):
            assert game.run_until(lambda g: server.machines[machine].state in states, 120.0), \
                (machine, server.machines[machine].state, states)

        def step(prepare=None, **task):
            """A task; ``prepare`` ((machine, instruction)): a feed, whose station is
            prepared once the robot waits docked at it (a station PREPARED too long
            before its workpiece comes breaks, as at a real refbox)."""
            tid = server.task(1, **task)
            if prepare is not None:
                machine, instruction = prepare
                assert game.run_until(lambda g: docked(server, 1, tid, server.machines[machine].zone), 240.0), \
                    (task, "the robot never waited at", machine)
                server.prepare(machine, **instruction)
            res = finish(game, server, tid, limit=240.0)
            assert res.successful, (task, server.error(tid))
            return res

        state(cs, "IDLE")
        step(buffer={"machine_id": cs, "shelf_number": 1},                      # a cap into the station
             prepare=(cs, {"cs": CS_OP["RETRIEVE_CAP"]}))
        state(cs, "READY-AT-OUTPUT")
        step(retrieve={"machine_id": cs, "machine_point": "output"})            # its empty carrier ...
        step(deliver={"machine_id": "C-RS1", "machine_point": "slide"})         # ... onto a slide
        server.prepare("C-BS", bs=(2, order.base_color))                        # a base at the output
        state("C-BS", "READY-AT-OUTPUT")
        step(retrieve={"machine_id": "C-BS", "machine_point": "output"})
        state(cs, "IDLE")
        step(deliver={"machine_id": cs, "machine_point": "input"},              # the cap on the base
             prepare=(cs, {"cs": CS_OP["MOUNT_CAP"]}))
        state(cs, "READY-AT-OUTPUT")
        step(retrieve={"machine_id": cs, "machine_point": "output"})            # the product
        step(deliver={"machine_id": "C-DS", "machine_point": "input"}, order_id=order.id,
             prepare=("C-DS", {"ds": order.id}))
        assert game.run_until(lambda g: any(d.order == order.id and d.team == "CYAN" for d in g.refbox.deliveries()),
                              20.0), (base, game.refbox.deliveries())
        assert game.status().points["CYAN"] > 0
    finally:
        game.close()
        server.close()


@pytest.mark.timeout(1800)
def test_rll_bts_team_server_drives_any_agenttask_robot():
    """``rll-bt teamserver --robots agenttask``: rll-bt's team server on a plain link,
    saying nothing but AgentTask, plays the game with the league robots above; under the
    2025 rules it prepares a feed's station once the beacons show the robot docked there
    (teamserver/links/docking.py).  Seed 8: the first delivery is the storage station's
    C0 (on seed 1 nothing was delivered within 900 s: a product built from the base up)."""
    from rll_bt.agenttask import link as agent_link
    from teamserver.links.refbox_link import udp_refbox_link
    from teamserver.server import ServerConfig, TeamServer
    p = free_ports(6)
    layout = Layout("test", public=PeerPorts(send=p[0], recv=p[1]), cyan=PeerPorts(send=p[2], recv=p[3]),
                    magenta=PeerPorts(send=p[4], recv=p[5]), stream=-1)
    listen = agent_link.tcp_server(0, host="127.0.0.1", key=None)
    game = ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", listen.port), TEAM, KEY, robots=3)],
                        profile="rcll2025", seed=8, layout=layout,
                        phases={"setup": 3.0, "exploration": 20.0, "production": 1200.0}, speed=SPEED)
    server = TeamServer("rcll2025", TEAM, clock=game.clock, key=KEY, agents=listen,
                        refbox=udp_refbox_link("rcll2025", BROADCAST, layout, clock=game.clock),
                        config=ServerConfig(robots="agenttask"))
    sent = []

    def tick(g):
        server.tick()
        sent.extend(m for where, m in server.sent if where != "refbox")
    game.hooks.append(tick)
    try:
        assert game.connect(timeout=30.0)
        assert game.run_until(lambda g: len(server.kb.active_robots()) == 3, 10.0)
        delivered = game.run_until(lambda g: any(d.team == "CYAN" for d in g.refbox.deliveries()), 1150.0)
        done = [t for t in server.kb.tasks.values() if t.state == "DONE" and t.kind != "go_to"]
        assert delivered, (game.status(), [(t.kind, t.params.get("machine")) for t in done])
        assert game.status().points["CYAN"] > 0
        assert sent and {m.DESCRIPTOR.full_name for m in sent} == {"llsf_msgs.AgentTask"}   # nothing else
        kinds = {t.kind for t in done}
        assert {"get_workpiece", "deliver"} <= kinds
    finally:
        game.close()
        server.close()
        listen.close()


@pytest.mark.timeout(1200)
def test_a_league_retrieve_from_a_shelf_takes_a_slot_that_holds_a_carrier():
    """``retrieve {CS, shelf}`` names no slot: the robot takes the carrier from the slot
    that holds one (twice in a row: two carriers), and answers NO_WORKPIECE_FOUND (202)
    when none does, and for an output that holds nothing."""
    game, server = make_game(robots=1, exploration=20.0, seed=8)
    try:
        assert in_production(game, server)
        assert game.run_until(lambda g: server.phase()[1] > 21.0 and len(server.machines) >= 7, 60.0)
        cs = min(("C-CS1", "C-CS2"), key=lambda m: server.machines[m].zone >= 1000)     # on our half first
        world = game.world.pybullet           # the PyBullet world itself (workpieces by hand)
        for slot in ("shelf0", "shelf1"):            # a referee's hand: only slot 2 holds a carrier
            assert world.remove_workpiece(cs, slot) is not None
        carrier = world.workpiece_at(cs, "shelf2")
        tid = server.task(1, retrieve={"machine_id": cs, "machine_point": "shelf"})
        res = finish(game, server, tid, limit=300.0)
        assert res.successful, server.error(tid)
        assert world.robot("CYAN", 1).holding == carrier.id
        slide = server.task(1, deliver={"machine_id": "C-RS1", "machine_point": "slide"})
        assert finish(game, server, slide, limit=240.0).successful, server.error(slide)
        # the refbox refilled the emptied shelf: two retrieves in a row take two carriers
        shelf = {slot: world.workpiece_at(cs, slot).id for slot in ("shelf0", "shelf1", "shelf2")}
        taken = []
        for _ in range(2):
            tid = server.task(1, retrieve={"machine_id": cs, "machine_point": "shelf"})
            res = finish(game, server, tid, limit=300.0)
            assert res.successful, server.error(tid)
            taken.append(world.robot("CYAN", 1).holding)
            slide = server.task(1, deliver={"machine_id": "C-RS1", "machine_point": "slide"})
            assert finish(game, server, slide, limit=240.0).successful, server.error(slide)
        assert taken == [shelf["shelf0"], shelf["shelf1"]]
        world.remove_workpiece(cs, "shelf2")          # the last one gone by hand: nothing on the shelf
        tid = server.task(1, retrieve={"machine_id": cs, "machine_point": "shelf"})
        res = finish(game, server, tid, limit=300.0)
        assert not res.successful and server.error(tid) == "NO_WORKPIECE_FOUND", (res, server.error(tid))
        assert world.robot("CYAN", 1).holding is None
        # nothing at the station's output (it was not prepared): nothing found, no grasp failed
        assert world.workpiece_at(cs, "output") is None
        tid = server.task(1, retrieve={"machine_id": cs, "machine_point": "output"})
        res = finish(game, server, tid, limit=300.0)
        assert not res.successful and server.error(tid) == "NO_WORKPIECE_FOUND", (res, server.error(tid))
        assert world.robot("CYAN", 1).holding is None
    finally:
        game.close()
        server.close()
