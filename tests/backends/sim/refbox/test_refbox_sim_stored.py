"""The simulated refbox plays a stored game: a game stored from one refbox and
played by another (another seed) has the same field, orders, ring colours and
costs and down periods, and plays them (orders activate and score as stored);
a refbox archive's game enters the same way; a world on another field is refused."""
from __future__ import annotations

import dataclasses
import json

import pytest

from backends.sim.refbox import RefboxGame, TableWorld, Timing
from backends.sim.refbox.stored_game import play_stored, store_game
from backends.sim.stored import StoredGame, load_game, read_refbox_games
from rll_bt.cli import main
from rll_bt.clock import SimClock
from rll_bt.rules import profile
from tests.support.refbox_archive import archive, report


def _game(rules: str, seed: int, world=None, **phases) -> RefboxGame:
    lengths = {"setup": 5.0, **({"exploration": 30.0} if rules == "rcll2016" else {}), **phases}
    return RefboxGame(rules, SimClock(), world, seed=seed, team_cyan="Caro",
                      timing=Timing.from_profile(profile(rules), **lengths))


def _orders(game):
    return [{k: v for k, v in dataclasses.asdict(o).items() if k not in ("active", "delivered")}
            for o in game.orders]


def _downs(game):
    return {m: st.down for m, st in game.stations.items() if st.down is not None}


@pytest.mark.parametrize("rules", ["rcll2016", "rcll2025"])
def test_a_stored_game_is_played_by_a_refbox_of_another_seed(rules, tmp_path):
    a = _game(rules, seed=3)
    path = tmp_path / "game.json"
    store_game(a).save(str(path))
    stored = load_game(str(path))
    b = _game(rules, seed=11, world=TableWorld(stored.layout()))
    before = _orders(b)
    play_stored(b, stored)
    assert before != _orders(a), "two seeds drew the same orders: the test shows nothing"
    assert _orders(b) == _orders(a)
    assert b.ring_costs == a.ring_costs
    assert {m: b.rs_colors(m) for m in b.stations} == {m: a.rs_colors(m) for m in a.stations}
    assert _downs(b) == _downs(a) and _downs(a)
    for m, pl in a.layout.machines.items():              # the field, each station's exact centre too
        q = b.layout[m]
        assert (q.zone, q.rotation_deg, q.pose.x, q.pose.y) == (pl.zone, pl.rotation_deg, pl.pose.x, pl.pose.y)
    assert list(b.layout.machines) == list(a.layout.machines)     # the world builds them in this order
    assert store_game(b, name=stored.name) == stored          # and stores back as it was read


def test_stored_orders_activate_and_open_as_stored():
    a = _game("rcll2025", seed=3)
    stored = store_game(a)
    late = dataclasses.replace(stored.orders[3], activate_at=250, delivery=(300, 500))
    stored = dataclasses.replace(stored, orders=stored.orders[:3] + (late,) + stored.orders[4:])
    b = _game("rcll2025", seed=3, world=TableWorld(stored.layout()))
    play_stored(b, stored)
    b.start()
    b.set_phase("PRODUCTION")
    b.advance(249.0)
    assert not b.order(late.id).active
    b.advance(2.0)
    o = b.order(late.id)
    assert o.active and (o.begin, o.end) == (300, 500)


def test_a_refbox_archive_game_enters_the_refbox():
    # a game report as the refbox stores it, on a whole field (seed 5's), with the report's orders,
    # ring specs, RS colours and down periods
    doc = report("benchmark_1")
    field = store_game(_game("rcll2025", seed=5))
    extra = {m["name"]: m for m in doc["machines"]}
    doc["machines"] = [{**extra.get(m, {}), "name": m, "zone": z, "rotation": r, "mtype": m[2:4]}
                       for m, (z, r) in field.machines.items()]
    stored = read_refbox_games(archive([doc]))[0]
    game = _game("rcll2025", seed=9, world=TableWorld(stored.layout()))
    play_stored(game, stored)
    assert [(o.id, o.complexity, o.base, o.rings, o.cap, o.begin, o.end, o.activate_at, o.competitive)
            for o in game.orders] == [(1, 0, "BASE_SILVER", (), "CAP_GREY", 0, 1020, 0, False),
                                      (6, 2, "BASE_RED", ("RING_BLUE", "RING_GREEN"), "CAP_BLACK", 401, 574, 172,
                                       True)]
    assert game.ring_costs == {"RING_GREEN": 2, "RING_BLUE": 1, "RING_ORANGE": 0, "RING_YELLOW": 0}
    assert game.rs_colors("C-RS1") == ("RING_BLUE", "RING_GREEN")
    assert _downs(game) == {"C-RS1": (300.0, 345.0), "M-RS1": (300.0, 345.0)}
    assert {m: (profile("rcll2025").zone_name(pl.zone), pl.rotation_deg)
            for m, pl in game.layout.machines.items()} == field.machines


def test_a_world_on_another_field_is_refused():
    stored = store_game(_game("rcll2025", seed=3))
    other = _game("rcll2025", seed=4)
    with pytest.raises(ValueError, match="build the world from the stored game's field"):
        play_stored(other, stored)
    with pytest.raises(ValueError, match="rcll2025"):
        play_stored(_game("rcll2016", seed=3), stored)


def test_the_refbox_command_reads_and_writes_stored_games(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    assert main(["refbox", "sim", "--team-cyan", "A", "--key", "k", "--game", str(bad), "--world", "table"]) == 2
    assert "not an rll-bt stored game" in capsys.readouterr().err
    good = tmp_path / "g.json"
    store_game(_game("rcll2025", seed=3)).save(str(good))
    assert main(["refbox", "sim", "--team-cyan", "A", "--key", "k", "--game", str(good), "--world", "table"]) == 2
    err = capsys.readouterr().err
    assert "rcll2025" in err and "--profile rcll2025" in err
    assert json.loads(good.read_text())["format"] == "rll-bt stored game"
    assert isinstance(load_game(str(good)), StoredGame)
