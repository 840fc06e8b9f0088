"""``rll-bt sim --refbox external``: a whole game whose refbox runs elsewhere.

The refbox here is our own simulated one in its network mode, as a process
of its own (``rll-bt refbox sim --world mqtt:... --time-sync --start
command``): it sees the world only over its real ports, exactly as the real
refbox would: its controller stream (SetTeamName, SetGamePhase,
SetGameState, SimTimeSync in; GameState, MachineInfo, OrderInfo out), UDP
with the team server and the agents, and its stations as MQTT machines
behind a real broker.  The game names the team, starts SETUP, builds the
world on the field the refbox announced, switches to PRODUCTION when the
robots are up and plays until POST_GAME; the refbox's clock follows the
world's (held while the world is held)."""
from __future__ import annotations

import json
import random
import socket
import subprocess
import sys

import pytest

from backends.sim.mps import Broker
from backends.sim.stored import load_game
from games import GameOptions
from games.external import ExternalGame
from rll_bt.rules import profile

pytestmark = [pytest.mark.slow,  # a whole game: `make test-fast` leaves it out
              pytest.mark.timeout(1500)]  # 255 s at a load of 50 on 2 cores

CLI_MAIN = "import sys; from rll_bt.cli import main; sys.exit(main())"
TEAM, KEY = "GRIPS", "external-test-key"
#: the refbox's game: SETUP until our game switches, 100 s of production, reports in its first 45 s
#: (the first base comes out of the BS at 45 s of game time, the second at 86 s)
PHASES = {"setup": 600.0, "exploration": 45.0, "production": 100.0}
STEPS = ("GET_BASE", "CAP_ACTION", "MOUNT_RING", "DELIVER", "RETRIEVE", "STORE")


def _free(port: int) -> bool:
    for kind in (socket.SOCK_STREAM, socket.SOCK_DGRAM):
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                return False
    return True


def free_offset() -> int:
    """A port offset whose refbox ports (the sim layout: 4441..4447) are all free."""
    for _ in range(200):
        off = random.randrange(2000, 20000, 10)
        if all(_free(p + off) for p in range(4441, 4448)):
            return off
    raise RuntimeError("no free port offset for a refbox")


@pytest.fixture
def refbox(tmp_path):
    """A broker and our refbox in network mode: (offset, broker address, snapshot file,
    the game it drew as a stored game)."""
    broker = Broker("amqtt")
    off = free_offset()
    snapshot, stored = tmp_path / "refbox.json", tmp_path / "refbox-game.json"
    lengths = ",".join(f"{k}={v:g}" for k, v in PHASES.items())
    log = open(tmp_path / "refbox.log", "w")  # noqa: SIM115 - closed below
    proc = subprocess.Popen(
        [sys.executable, "-c", CLI_MAIN, "refbox", "sim", "--profile", "rcll2025", "--team-cyan", TEAM,
         "--key-cyan", KEY, "--seed", "6", "--host", "127.255.255.255", "--port-offset", str(off),
         "--world", f"mqtt:{broker.host}:{broker.port}", "--time-sync", "--start", "command",
         "--phase-lengths", lengths, "--snapshot", str(snapshot), "--snapshot-period", "0.5",
         "--save-game", str(stored)],
        stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        yield off, f"{broker.host}:{broker.port}", snapshot, stored
    finally:
        proc.terminate()
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()
        broker.stop()
        print((tmp_path / "refbox.log").read_text()[-3000:])


def _driven(hall) -> dict[str, list[str]]:
    """Each station's step commands that came over MQTT, and what it did."""
    out = {}
    for m in hall:
        cmds = [r.text for r in m.records if r.text.startswith("command ") and r.text.split()[1] in STEPS]
        if cmds:
            out[m.name] = cmds
    return out


def test_a_whole_game_against_a_refbox_over_its_network_protocol(refbox, tmp_path):
    off, broker, snapshot, stored = refbox
    options = GameOptions(profile="rcll2025", seed=6, robots=2, strategy="oracle", refbox="external",
                          refbox_port_offset=off, mqtt=broker, team_name=TEAM, key=KEY, processes=True,
                          out=tmp_path / "game", setup=PHASES["setup"], exploration=PHASES["exploration"],
                          production=PHASES["production"], refbox_timeout=120.0)
    game = ExternalGame(options, connect_timeout=120.0)
    try:
        assert game.refbox.status().phase == "SETUP"
        # the world stands on the refbox's field (as it drew it, not as a seed would)
        field, rules = load_game(str(stored)), profile("rcll2025")
        assert {n: (rules.zone_name(st.zone), st.rotation) for n, st in game.refbox.stations().items()} \
            == dict(field.machines)
        link = game.refbox.link
        assert game.run_until(lambda g: g.refbox.status().phase == "PRODUCTION", limit=120.0)
        # the world held: the refbox's clock stands still with it
        game.run_for(2.0)
        g0, w0 = link.status().game_time, game.clock.now()
        wall0 = game.wall.now()
        game.hold(4.0)
        n = link.received
        game.run_until(lambda g: link.received > n + 2 and g.clock.now() > w0 + 2.0, limit=20.0)
        dg, dw, dwall = link.status().game_time - g0, game.clock.now() - w0, game.wall.now() - wall0
        assert dwall - dw > 3.0, "the world was not held"
        assert abs(dg - dw) < 1.5, f"the refbox's clock ran {dg:.1f} s over {dw:.1f} world s ({dwall:.1f} s wall)"
        result = game.run()
        driven = _driven(game.refbox.hall)
    finally:
        game.close()
    truth = json.loads(snapshot.read_text())
    assert result.finished and result.status.phase == "POST_GAME"
    # what the game reports is what the refbox decided
    assert result.status.points["CYAN"] == truth["status"]["points"]["CYAN"] > 0
    assert sum(a.points for a in result.awards) == truth["status"]["points"]["CYAN"]
    # the team server and the agents played on the refbox's ports: reports scored, stations prepared
    reasons = [(a["points"], a["reason"]) for a in truth["awards"]]
    assert any("correct zone" in r for _, r in reasons), reasons
    prepared = {e["machine"] for e in truth["station_log"] if e["to"] == "PROCESSING"}
    assert prepared, f"the refbox prepared no station; its awards: {reasons}"
    # ... and the refbox worked the world's stations over MQTT: each prepared station got its steps
    assert set(driven) >= prepared, (driven, prepared)
