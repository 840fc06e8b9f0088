"""A short whole rcll2025 game in lockstep: exploration by zone and rotation
inside PRODUCTION, the 2025 MachineReport, production, and the DS prepared
with the order id (the 2025 instruction) for the first delivery."""
import json
import re

import pytest

from tests.support.games import PRODUCTION_KINDS, short_game

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out

EXPLORE_AWARD = re.compile(r"correct (zone|rotation) (\S+) for (\S+)$")


def test_a_short_2025_game_scores_zone_and_rotation_and_delivers_by_order_id(tmp_path):
    # 40 s of exploration at the start of PRODUCTION; stop at the first delivery (about
    # 250 s in).  PRODUCTION as long as the rules' 1200 s: the order windows scale with
    # the phase, and at 600 s they were half as long as the real schedule's (a C2 had
    # 84 s from 144 s, less than the real machines take to build it: it was late)
    with short_game(seed=3, profile="rcll2025", production=1200.0, out=tmp_path) as game:
        prof = game.options.rules
        result = game.run(stop=lambda g: any(d.team == "CYAN" for d in g.refbox.deliveries()))
        truth = {n: s for n, s in game.refbox.stations().items() if s.team == "CYAN"}
        snap = game.teamserver.snapshot()
    assert result.finished and result.status.phase == "PRODUCTION"

    # exploration: zone and rotation awards, each right, a rotation only after its zone
    explored = [(a, EXPLORE_AWARD.match(a.reason)) for a in result.awards
                if a.team == "CYAN" and a.order is None and EXPLORE_AWARD.match(a.reason)]
    assert sum(a.points for a, _ in explored) > 0
    assert all(a.points > 0 for a, _ in explored), "a wrong report was penalised"
    zone_at = {}
    for a, m in explored:
        what, value, machine = m.groups()
        assert machine in truth, a
        if what == "zone":
            assert value == prof.zone_name(truth[machine].zone), a
            zone_at[machine] = a.game_time
        else:
            assert int(value) == truth[machine].rotation, a
            assert machine in zone_at and zone_at[machine] <= a.game_time, f"rotation before zone: {a}"
    rotations = {m.group(3) for _, m in explored if m.group(1) == "rotation"}
    assert rotations, "no rotation was scored"

    lines = [json.loads(x) for x in (tmp_path / "messages.jsonl").read_text().splitlines()]
    # MachineReport, 2025 form: the team channel, C_Zxy/M_Zxy zone names, rotation in degrees
    reports = [x for x in lines if x["type"] == "MachineReport" and x["from"] == "teamserver"]
    assert reports and all(x["channel"] == "cyan" and x["msg"]["team_color"] == "CYAN" for x in reports)
    entries = [e for x in reports for e in x["msg"]["machines"]]
    assert all(re.fullmatch(r"[CM]_Z\d\d", e["zone"]) for e in entries)
    assert all(e["rotation"] in range(0, 360, 45) for e in entries if "rotation" in e)
    last = {e["name"]: e for e in reports[-1]["msg"]["machines"]}
    assert rotations <= {n for n, e in last.items() if "rotation" in e}
    for name, e in last.items():
        assert e["zone"] == prof.zone_name(truth[name].zone), e
        assert e.get("rotation", truth[name].rotation) == truth[name].rotation, e

    # production: bases fetched, steps done, the DS prepared with the delivered order's id
    prepares = [x["msg"] for x in lines if x["type"] == "PrepareMachine"]
    assert any("instruction_bs" in p for p in prepares if p["machine"] == "C-BS")
    assert any(t["kind"] in PRODUCTION_KINDS and t["state"] == "DONE" for t in snap["tasks"])
    delivery = next(d for d in result.deliveries if d.team == "CYAN")
    assert delivery.how == "in-time" and delivery.points > 0
    ds = [p["instruction_ds"] for p in prepares if p["machine"] == "C-DS"]
    assert ds and all(set(d) == {"order_id"} for d in ds), ds      # no 2016 gate
    assert delivery.order in {d["order_id"] for d in ds}
