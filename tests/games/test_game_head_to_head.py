"""Two teams on one field: ``rll-bt sim --cyan CONFIG --magenta CONFIG`` in
lockstep and in processes, six robots, each team its own team server, key
and agents; the other team's robots met only in the lasers; a competitive
2025 order paying the first team and costing the second."""
from __future__ import annotations

import json
from dataclasses import replace

import pytest

from games import GameOptions, LockstepGame, finish
from rll_bt.cli import main

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out

OURS = {"cyan": ("teamserver-cyan", "C-R"), "magenta": ("teamserver-magenta", "M-R")}


def _senders_keep_to_their_team(log: list[dict]) -> None:
    """Each team channel carries only the refbox, its team server and its robots;
    each team server's link only its own robots."""
    for color, (server, prefix) in OURS.items():
        on_channel = {x["from"] for x in log if x["channel"] == color}
        assert {"refbox", server} <= on_channel and any(f.startswith(prefix) for f in on_channel), on_channel
        assert all(f in ("refbox", server) or f.startswith(prefix) for f in on_channel), on_channel
        on_link = {x["from"] for x in log if x["channel"] == server}
        assert server in on_link and all(f == server or f.startswith(prefix) for f in on_link), on_link


def test_a_lockstep_head_to_head_game_both_teams_score_and_never_touch(tmp_path):
    out = tmp_path / "game"
    options = GameOptions(cyan="htn", magenta="baseline", seed=3, setup=1.0, exploration=40.0, production=60.0,
                          overtime=0.0, strategy="oracle", out=out)
    with LockstepGame(options) as game:
        result = game.run()
        summary = finish(result, options)
        snaps = {c: side.teamserver.snapshot() for c, side in game.sides.items()}
    assert result.finished
    rep = json.loads((out / "report.json").read_text())
    assert rep["sim_time"] < 1 + 40 + 60 + 5                 # overtime=0: a tie would not have added 300 s
    m = rep["match"]
    assert m["labels"] == {"CYAN": "htn", "MAGENTA": "baseline"}
    assert m["points"]["CYAN"] > 0 and m["points"]["MAGENTA"] > 0            # both teams scored
    teams = rep["teams"]
    for color in ("CYAN", "MAGENTA"):
        assert teams[color]["points"]["exploration"] > 0
        assert set(teams[color]["robot_stats"]) == {"1", "2", "3"}           # six robots on the field
        assert all(s["distance"] > 1.0 for s in teams[color]["robot_stats"].values())
        # each team server knows its own three robots, all active, and no other
        robots = snaps[color]["robots"]
        assert {str(n) for n, r in robots.items() if r["status"] == "ACTIVE"} == {"1", "2", "3"} \
            and len(robots) == 3 and snaps[color]["color"] == color
    assert m["collisions_between_teams"] == 0
    assert m["collisions_within_teams"] == {"CYAN": 0, "MAGENTA": 0}
    # they met: the lasers of both teams saw robots of the other team
    seen = m["other_team_in_laser_scans"]
    assert any(r.startswith("CYAN/") for r in seen) and any(r.startswith("MAGENTA/") for r in seen)
    log = [json.loads(x) for x in (out / "messages.jsonl").read_text().splitlines()]
    _senders_keep_to_their_team(log)
    assert "htn" in summary["table"] and "baseline" in summary["table"]
    assert all((out / p).stat().st_size > 0 for p in ("field.png", "timeline.png", "score.png"))


@pytest.mark.timeout(900)          # nine processes, a whole short game on the wall clock (> 300 s on a 2-core CI)
def test_a_head_to_head_game_in_processes(tmp_path):
    out = tmp_path / "game"
    rc = main(["sim", "--processes", "--cyan", "baseline", "--magenta", "htn", "--seed", "2", "--setup", "1",
               "--exploration", "40", "--production", "10", "--overtime", "0", "--strategy", "oracle",
               "--out", str(out), "-q"])
    assert rc == 0, sorted(p.name for p in out.iterdir())
    rep = json.loads((out / "report.json").read_text())
    m = rep["match"]
    assert m["labels"] == {"CYAN": "baseline", "MAGENTA": "htn"}
    for color in ("CYAN", "MAGENTA"):
        assert rep["teams"][color]["points"]["exploration"] > 0              # both teams reported stations
        assert set(rep["teams"][color]["robot_stats"]) == {"1", "2", "3"}
    assert m["collisions_between_teams"] == 0
    # each part its own process: one refbox, two team servers, six agents, each with its log
    for name in ("refbox", "teamserver-cyan", "teamserver-magenta", *(f"agent-{c}{n}" for c in ("cyan", "magenta")
                                                                       for n in (1, 2, 3))):
        assert (out / f"{name}.log").exists(), name
    for color in ("cyan", "magenta"):
        snap = json.loads((out / f"teamserver-{color}.json").read_text())
        assert {n for n, r in snap["robots"].items() if r["status"] == "ACTIVE"} == {"1", "2", "3"}
    refbox = json.loads((out / "refbox.json").read_text())
    assert refbox["status"]["points"] == m["points"]
    log = [json.loads(x) for x in (out / "messages.jsonl").read_text().splitlines()]
    _senders_keep_to_their_team(log)
    assert all((out / p).stat().st_size > 0 for p in ("field.png", "timeline.png", "score.png"))


def _both_delivered_one_order(game) -> bool:
    got = {c: {d.order for d in game.refbox.deliveries() if d.team == c and d.how == "in-time"}
           for c in ("CYAN", "MAGENTA")}
    return bool(got["CYAN"] & got["MAGENTA"])


@pytest.mark.timeout(1200)
def test_a_competitive_order_pays_the_first_team_and_costs_the_second():
    """2025 rules: the first team to deliver a competitive order gains 10, the
    other team's delivery of it loses up to 10.  The game's orders are cut to
    one competitive C0 order, open from the start of production, so that both
    teams make the same product at once (with the drawn orders both teams first
    deliver the same order only after ~470 s of game time)."""
    options = GameOptions(seed=3, cyan="htn", magenta="htn", profile="rcll2025", setup=1.0, exploration=40.0,
                          production=600.0, strategy="oracle")
    with LockstepGame(options) as game:
        orders = game.refbox.game.orders
        orders[:] = [replace(orders[0], id=1, complexity=0, rings=(), quantity=1, begin=0, end=600,
                             activate_at=0, standing=False, overtime=False, competitive=True)]
        result = game.run(stop=_both_delivered_one_order)
    assert _both_delivered_one_order(game), [(d.team, d.order, d.how) for d in result.deliveries]
    both = sorted({d.order for d in result.deliveries if d.team == "CYAN"}
                  & {d.order for d in result.deliveries if d.team == "MAGENTA"})
    assert both == [1]
    firsts = [a for a in result.awards if a.reason == "first delivery for competitive order 1"]
    seconds = [a for a in result.awards if a.reason == "second delivery for competitive order 1"]
    assert len(firsts) == 1 and len(seconds) == 1
    assert firsts[0].points == 10 and seconds[0].points < 0
    assert firsts[0].team != seconds[0].team                                # one team won it, the other paid
    assert firsts[0].game_time <= seconds[0].game_time
    assert not any(c[2].startswith("robot ") and c[1][0] != c[2][6] for c in result.collision_log)
