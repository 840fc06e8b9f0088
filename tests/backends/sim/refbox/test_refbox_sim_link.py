"""The station link: the refbox's calls applied in the world, the robots' puts and takes
and the operator's commands delivered in order, a slow side waited for, a closed link
reported clearly; a refbox game over it on the PyBullet world; and ``rll-bt refbox sim
--world remote:...`` as its own process."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from backends.sim.refbox import BSInstruction, RefboxGame, RSInstruction, TableWorld, Workpiece
from backends.sim.refbox.link import RemoteWorld, StationServer
from backends.sim.refbox.world import WorldLost
from rll_bt.comm import free_ports

RLL_BT = str(Path(sys.executable).parent / "rll-bt")


class RefboxSide:
    """The refbox's process played by one worker thread; this thread is the world's,
    serving the link while it waits for the refbox's side to finish something."""

    def __init__(self, server: StationServer):
        self.server = server
        self.pool = ThreadPoolExecutor(max_workers=1)

    def do(self, fn, *, serve: bool = True, timeout: float = 20.0):
        fut = self.pool.submit(fn)
        end = time.monotonic() + timeout
        while not fut.done():
            assert time.monotonic() < end, "the refbox side hangs"
            if serve:
                self.server.poll(0.005)
            else:
                time.sleep(0.005)
        return fut.result()

    def close(self) -> None:
        self.pool.shutdown(wait=True)


@pytest.fixture
def table():
    world = TableWorld.generated("rcll2016", 3)
    server = StationServer(world)
    side = RefboxSide(server)
    remote = side.do(lambda: RemoteWorld(f"127.0.0.1:{server.port}", timeout=5.0))
    yield world, server, side, remote
    remote.close()
    side.close()
    server.close()


def test_calls_are_applied_in_the_world(table):
    world, server, side, remote = table
    assert remote.layout.to_dict() == world.layout.to_dict()         # the world's layout, as it said at connecting
    side.do(lambda: remote.set_lights("C-BS", green="ON", yellow="BLINK"))
    assert world.lights("C-BS") == {"RED": "OFF", "YELLOW": "BLINK", "GREEN": "ON"}
    assert side.do(lambda: remote.lights("C-BS"))["GREEN"] == "ON"
    wp = side.do(lambda: remote.spawn_workpiece("C-BS", "output", "BASE_RED"))
    assert world.workpiece_at("C-BS", "output") == Workpiece("BASE_RED") and wp.id == world.workpiece_at(
        "C-BS", "output").id
    side.do(lambda: remote.spawn_workpiece("C-RS1", "slide", "BASE_RED"))
    side.do(lambda: remote.spawn_workpiece("C-RS1", "slide", "BASE_BLACK"))
    assert [w.base for w in side.do(lambda: remote.workpieces_at("C-RS1", "slide"))] == ["BASE_RED", "BASE_BLACK"]
    assert side.do(lambda: remote.workpiece_at("C-BS", "output")) == Workpiece("BASE_RED")
    with pytest.raises(ValueError, match="occupied"):                 # the world's own errors, by kind
        side.do(lambda: remote.spawn_workpiece("C-BS", "output", "BASE_RED"))
    with pytest.raises(KeyError, match="no station"):
        side.do(lambda: remote.workpiece_at("C-XX", "input"))
    assert side.do(lambda: remote.remove_workpiece("C-BS", "output")) == Workpiece("BASE_RED")
    assert world.workpiece_at("C-BS", "output") is None
    assert side.do(lambda: remote.remove_workpiece("C-BS", "output")) is None


def test_slot_events_and_commands_arrive_in_order(table):
    world, server, side, remote = table
    got = []
    remote.add_slot_listener(lambda ev: got.append((ev.kind, ev.machine, ev.slot, str(ev.workpiece))))
    remote.on_command(lambda cmd: got.append(("command", cmd["op"], cmd.get("machine"))))
    world.put("C-CS1", "input", Workpiece("BASE_RED"))               # a robot's puts and takes, in the world
    server.command("down", machine="C-CS1", seconds=30.0)
    world.take("C-CS1", "input")
    world.put("C-RS1", "slide", Workpiece("BASE_BLACK"))
    server.command("start")
    assert got == []                                                  # nothing until the refbox pumps
    deadline = time.monotonic() + 5
    while len(got) < 5 and time.monotonic() < deadline:
        side.do(remote.pump)
    assert got == [("put", "C-CS1", "input", "BASE_RED"), ("command", "down", "C-CS1"),
                   ("take", "C-CS1", "input", "BASE_RED"), ("put", "C-RS1", "slide", "BASE_BLACK"),
                   ("command", "start", None)]


def test_events_before_the_refbox_connects_wait_for_it():
    world = TableWorld.generated("rcll2016", 3)
    server = StationServer(world)
    side = RefboxSide(server)
    try:
        world.put("C-DS", "input", Workpiece("BASE_RED", cap="CAP_GREY"))
        with pytest.raises(RuntimeError, match="no refbox"):
            server.command("start")
        remote = side.do(lambda: RemoteWorld(f"127.0.0.1:{server.port}"))
        got = []
        remote.add_slot_listener(got.append)
        for _ in range(20):
            server.poll(0.01)
            side.do(remote.pump)
        assert [(e.kind, e.machine, e.workpiece.cap) for e in got] == [("put", "C-DS", "CAP_GREY")]
        remote.close()
    finally:
        side.close()
        server.close()


def test_a_slow_world_is_waited_for_and_a_slow_refbox_misses_nothing(table):
    world, server, side, remote = table
    # the world does not serve for 1.5 s (a long physics step): the call waits for it
    t0 = time.monotonic()
    fut = side.pool.submit(lambda: remote.spawn_workpiece("C-BS", "input", "BASE_SILVER"))
    time.sleep(1.5)
    assert not fut.done()
    while not fut.done():
        server.poll(0.01)
    assert fut.result().base == "BASE_SILVER" and time.monotonic() - t0 >= 1.5
    # the refbox reads nothing while robots put and take 40000 times: the world never blocks on it
    remote.add_slot_listener(lambda ev: seen.append(ev.workpiece.id))
    seen: list[int] = []
    ids = []
    t0 = time.monotonic()
    for _ in range(20000):
        ids.append(world.put("C-RS2", "input", Workpiece("BASE_RED")).id)
        world.take("C-RS2", "input")
        ids.append(ids[-1])
    assert time.monotonic() - t0 < 10.0
    assert server.unsent > 0                     # what the socket would not take waits in the server's buffer
    deadline = time.monotonic() + 20
    while len(seen) < len(ids) and time.monotonic() < deadline:
        server.poll(0.01)
        side.do(remote.pump)
    assert seen == ids


def test_a_closed_link_is_reported_clearly(table):
    world, server, side, remote = table
    server.close()
    with pytest.raises(WorldLost, match=r"the world at 127\.0\.0\.1:\d+ closed the station link"):
        side.do(lambda: remote.workpiece_at("C-BS", "output"), serve=False)
    with pytest.raises(WorldLost, match="closed"):
        side.do(remote.pump, serve=False)
    port = free_ports(1, tcp=True)[0]
    with pytest.raises(WorldLost, match=f"cannot reach the world at 127.0.0.1:{port}"):
        RemoteWorld(f"127.0.0.1:{port}")


@pytest.mark.slow
def test_a_refbox_game_over_the_link_on_the_pybullet_world():
    """As tests/refbox_sim/test_refbox_sim_world.py's first test, the refbox on the other
    side of the link: a base dispensed is in the world when the refbox says so, the
    robot's take and put reach the refbox, the ring station processes."""
    from backends.sim.world import World
    world = World("rcll2016", seed=5)
    server = StationServer(world)
    side = RefboxSide(server)
    try:
        remote = side.do(lambda: RemoteWorld(f"127.0.0.1:{server.port}"))
        g = side.do(lambda: RefboxGame("rcll2016", world.clock, remote, seed=5, team_cyan="A", team_magenta="B"))
        assert world.workpiece_at("C-CS1", "shelf0").cap == "CAP_GREY"     # the carriers, spawned over the link
        side.do(g.start)
        side.do(lambda: g.set_phase("PRODUCTION"))
        assert world.lights("C-BS") == {"RED": "OFF", "YELLOW": "OFF", "GREEN": "ON"}

        def tick():
            remote.pump()
            g.tick()

        def run(seconds):
            world.run(seconds, callback=lambda t: side.do(tick))
        robot = world.add_robot("CYAN", 1)
        side.do(lambda: g.prepare("CYAN", "C-BS", BSInstruction("OUTPUT", "BASE_RED"), "CYAN"))
        seen = []
        for _ in range(60):
            run(0.1)
            if g.stations["C-BS"].state == "READY-AT-OUTPUT":
                seen.append(world.workpiece_at("C-BS", "output"))
                break
        assert seen and seen[0].base == "BASE_RED"             # in the world once the refbox says it is ready
        world.teleport("CYAN", 1, world.station("C-BS").approach_pose("output"))
        robot.gripper.command("close", now=world.time)
        run(3)
        assert world.held_workpiece("CYAN", 1).base == "BASE_RED"
        assert g.stations["C-BS"].state == "WAIT-IDLE"        # the take was seen across the link
        color = next(c for c in g.rs_colors("C-RS1") if g.ring_costs[c] == 0)
        side.do(lambda: g.prepare("CYAN", "C-RS1", RSInstruction(color), "CYAN"))
        world.teleport("CYAN", 1, world.station("C-RS1").approach_pose("input"))
        robot.gripper.command("open", now=world.time)
        run(3)
        assert g.stations["C-RS1"].state == "PROCESSING"      # and the put
        run(20)
        wp = world.workpiece_at("C-RS1", "output")
        assert (wp.base, wp.rings) == ("BASE_RED", (color,))
        assert world.lights("C-RS1") == {"RED": "OFF", "YELLOW": "ON", "GREEN": "OFF"}
        remote.close()
    finally:
        side.close()
        server.close()
        world.close()


def _wait(server, until, seconds=20.0):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        server.poll(0.02)
        if until():
            return True
    return False


def test_refbox_sim_on_a_remote_world_as_its_own_process(tmp_path):
    """Started by the world's command, a station DOWN on command, the world's end
    reported in one line (exit 3, no traceback); SIGTERM ends it cleanly."""
    world = TableWorld.generated("rcll2016", 3)
    snap = tmp_path / "refbox.json"
    p = free_ports(6)
    ports = f"public={p[0]}/{p[1]},cyan={p[2]}/{p[3]},magenta={p[4]}/{p[5]}"

    def start(server):
        return subprocess.Popen(
            [RLL_BT, "refbox", "sim", "--team-cyan", "Caro", "--key", "k", "--seed", "3", "--ports", ports,
             "--no-stream", "--start", "command", "--world", f"remote:127.0.0.1:{server.port}",
             "--phase-lengths", "setup=0.3,exploration=0.5,production=60", "--snapshot", str(snap),
             "--snapshot-period", "0.1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def read():
        try:
            return json.loads(snap.read_text())
        except (OSError, ValueError):
            return {}

    server = StationServer(world)
    proc = start(server)
    try:
        assert _wait(server, lambda: read().get("status", {}).get("phase") == "PRE_GAME"), proc.stderr.read()
        assert read()["pid"] == proc.pid
        assert world.workpiece_at("C-CS1", "shelf0") is not None          # the refbox's carriers, in this world
        server.command("start")
        assert _wait(server, lambda: read()["status"]["phase"] == "PRODUCTION")
        server.command("down", machine="C-BS", seconds=30.0)
        assert _wait(server, lambda: read()["stations"]["C-BS"]["state"] == "DOWN")
        server.close()                                                     # the world's process ends
        out, err = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
        server.close()
    assert proc.returncode == 3, err
    assert "closed the station link" in err and "Traceback" not in err and len(err.strip().splitlines()) <= 2
    assert "the world was lost" in out
    assert read()["status"]["phase"] == "PRODUCTION"                       # the last snapshot, written at exit

    server = StationServer(TableWorld.generated("rcll2016", 3))
    proc = start(server)
    try:
        assert _wait(server, lambda: read().get("pid") == proc.pid)
        proc.send_signal(signal.SIGTERM)
        while proc.poll() is None:
            server.poll(0.02)
        out, err = proc.communicate(timeout=5)
    finally:
        if proc.poll() is None:
            proc.kill()
        server.close()
    assert proc.returncode == 0 and "Traceback" not in err and "stopped by signal" in out


def test_the_refbox_process_keeps_the_worlds_time(tmp_path):
    """A process game's world may fall behind the wall clock (a loaded machine, a long
    physics step); the refbox's process runs its game on the world's time, pushed over
    the link, so a world at a quarter of real time plays a quarter of the game's
    seconds, as the world's robots live them."""
    world = TableWorld.generated("rcll2016", 3)
    snap = tmp_path / "refbox.json"
    p = free_ports(6)
    server = StationServer(world)
    proc = subprocess.Popen(
        [RLL_BT, "refbox", "sim", "--team-cyan", "Caro", "--key", "k", "--seed", "3", "--ports",
         f"public={p[0]}/{p[1]},cyan={p[2]}/{p[3]},magenta={p[4]}/{p[5]}", "--no-stream", "--start", "command",
         "--world", f"remote:127.0.0.1:{server.port}", "--phase-lengths", "setup=0.5,exploration=600,production=60",
         "--snapshot", str(snap), "--snapshot-period", "0.05"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True)

    def read():
        try:
            return json.loads(snap.read_text())
        except (OSError, ValueError):
            return {}
    w0, t0 = time.monotonic(), 100.0

    def world_time():                   # a world running at a quarter of the wall clock's pace
        t = t0 + 0.25 * (time.monotonic() - w0)
        server.clock(t)
        return t

    def run(until, seconds=30.0):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            world_time()
            server.poll(0.01)
            if until():
                return True
        return False
    try:
        assert run(lambda: read().get("status", {}).get("phase") == "PRE_GAME"), proc.stderr.read()
        server.command("start")
        assert run(lambda: read()["status"]["phase"] == "EXPLORATION")
        first = read()["now"], world_time()
        run(lambda: world_time() - first[1] >= 1.0)                   # one world second: four on the wall
        held = world_time()
        end = time.monotonic() + 1.5
        while time.monotonic() < end:                                 # then the world stalls for 1.5 s
            server.poll(0.01)
        game = read()["now"] - first[0]
        assert held - first[1] - 0.3 <= game <= held - first[1] + 0.15, (game, held - first[1])
    finally:
        proc.kill()
        proc.communicate()
        server.close()
