"""The parts of a tournament without playing a game: the schedule, the store,
the table, the executors on a stand-in game, and the command's usage errors."""
from __future__ import annotations

from types import SimpleNamespace

import pytest

from games import report
from games.tournament import run_tournament
from games.tournament.executors import LocalExecutor, open_executor
from games.tournament.schedule import Match, round_robin, settings
from games.tournament.store import Store, StoreError
from games.tournament.table import games_csv, render, standings
from rll_bt.cli import main
from rll_bt.comm.ports import free_ports


def test_every_pair_meets_on_every_seed_in_both_colours():
    games = round_robin(["htn", "baseline", "htn:strategy=nearest"], [1, 2], settings())
    pairs = {(m.cyan, m.magenta, m.seed) for m in games}
    assert len(games) == len(pairs) == 3 * 2 * 2
    assert ("htn", "baseline", 1) in pairs and ("baseline", "htn", 1) in pairs
    assert [m.seed for m in games] == sorted(m.seed for m in games)       # whole seeds first
    assert Match.from_dict(games[0].to_dict()) == games[0]


@pytest.mark.parametrize("configs,message", [
    (["htn"], "at least two"), (["htn", "htn"], "given twice"), (["htn", "external"], "external"),
    (["htn", "baseline:robots=7"], "robots"), (["htn", ":x"], "give a kind")])
def test_bad_configurations_are_refused(configs, message):
    with pytest.raises(ValueError, match=message):
        round_robin(configs, [1], settings())


def _row(cyan, magenta, seed, pc, pm):
    return {"key": Match(cyan, magenta, seed).key, "cyan": cyan, "magenta": magenta, "seed": seed,
            "points": {"cyan": pc, "magenta": pm},
            "winner": None if pc == pm else (cyan if pc > pm else magenta), "error": None}


def test_the_table_counts_wins_losses_draws_points_and_the_best_game():
    rows = [_row("a", "b", 1, 50, 30), _row("b", "a", 1, 40, 40), _row("a", "b", 2, 10, 90),
            _row("b", "a", 2, 20, 70), {"key": "b | a | 3", "cyan": "b", "magenta": "a", "seed": 3,
                                         "error": "RuntimeError: boom"}]
    st = {s["config"]: s for s in standings(["a", "b"], rows)}
    assert (st["a"]["games"], st["a"]["wins"], st["a"]["losses"], st["a"]["draws"]) == (4, 2, 1, 1)
    assert (st["a"]["points_for"], st["a"]["points_against"]) == (170, 180)
    assert (st["b"]["wins"], st["b"]["losses"], st["b"]["points_for"]) == (1, 2, 180)
    assert st["a"]["best"] == {"points": 70, "against": 20, "opponent": "b", "color": "magenta", "seed": 2}
    assert st["b"]["best"]["points"] == 90
    text = render(["a", "b"], rows, planned=6)
    assert text.splitlines()[2].startswith("a ") and "4 games of 6, 1 failed" in text
    assert "RuntimeError: boom" in games_csv(rows)


def test_collisions_are_counted_between_the_teams_within_each_team_and_with_the_field():
    log = [(1.0, "CYAN/1", "robot MAGENTA/2"), (2.0, "MAGENTA/3", "robot MAGENTA/1"),
           (3.0, "MAGENTA/1", "robot MAGENTA/3"), (4.0, "CYAN/2", "C-CS1"), (5.0, "CYAN/3", "wall")]
    result = SimpleNamespace(status=SimpleNamespace(points={"CYAN": 10, "MAGENTA": 10}), sightings={},
                             recordings={"CYAN": None, "MAGENTA": None}, labels={}, collision_log=log)
    m = report.match(result)
    assert m["collisions_between_teams"] == 1
    assert m["collisions_within_teams"] == {"CYAN": 0, "MAGENTA": 2}
    assert report._collision_kinds(log) == {"robot": 3, "station": 1, "wall": 1}
    row = {**_row("a", "b", 1, 10, 10), "collisions_between_teams": 1,
           "collisions_within_teams": {"cyan": 0, "magenta": 2}, "collisions_with": {"station": 1, "wall": 1}}
    head, line = games_csv([row]).splitlines()
    got = dict(zip(head.split(","), line.split(",")))
    assert (got["collisions_between_teams"], got["cyan_collisions_within"], got["magenta_collisions_within"],
            got["collisions_with_stations"], got["collisions_with_walls"]) == ("1", "0", "2", "1", "1")


def test_the_store_keeps_rows_and_refuses_other_settings(tmp_path):
    with Store(tmp_path, settings(production=60.0)) as s:
        s.add(_row("a", "b", 1, 5, 3))
        s.add(_row("b", "a", 1, 2, 2))
    with Store(tmp_path, settings(production=60.0)) as s:
        assert list(s.rows()) == ["a | b | 1", "b | a | 1"]
    with pytest.raises(StoreError, match="production 60.0 there, 120.0 now"):
        Store(tmp_path, settings(production=120.0))
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "tournament.sqlite").write_text("not a database" * 100)
    with pytest.raises(StoreError, match="not a tournament store"):
        Store(tmp_path / "x", settings())


def _fake_game(data: dict) -> dict:
    """A stand-in for a game: a score made from the seed and the names."""
    m = Match.from_dict(data)
    if m.seed == 99:
        raise RuntimeError("lost")
    return _row(m.cyan, m.magenta, m.seed, m.seed * len(m.cyan), m.seed * len(m.magenta))


def test_a_resumed_tournament_plays_only_the_missing_games(tmp_path):
    first = run_tournament(["htn", "baseline"], [1], tmp_path, play=_fake_game, production=30.0)
    assert first["played"] == 2
    more = run_tournament(["htn", "baseline"], [1, 2], tmp_path, play=_fake_game, production=30.0)
    assert more["played"] == 2 and len(more["rows"]) == 4
    again = run_tournament(["htn", "baseline"], [1, 2], tmp_path, play=_fake_game, production=30.0)
    assert again["played"] == 0 and again["table"] == more["table"]
    assert {p.name for p in tmp_path.iterdir()} >= {"tournament.sqlite", "games.csv", "table.txt", "scores.png"}


def test_a_game_its_worker_loses_is_an_error_row_not_a_lost_tournament():
    with LocalExecutor(1) as ex:
        got = dict(ex.run(_fake_game, [Match("a", "b", 99).to_dict(), Match("a", "b", 1).to_dict()]))
    assert "lost" in got[0]["error"] and got[1]["points"] == {"cyan": 1, "magenta": 1}



@pytest.mark.timeout(300)     # before: the pool stopped for good after 4 games (a hang, not a slow run)
def test_the_local_pool_plays_more_games_than_its_workers_task_limit():
    """Each worker process plays a bounded number of games, then a new one takes its place; a
    tournament of more games than that goes on to the end (2 workers stopped after 8 of 40)."""
    matches = [Match("a", "b", seed).to_dict() for seed in range(1, 11)]
    with LocalExecutor(1) as ex:
        got = dict(ex.run(_fake_game, matches))
    assert sorted(got) == list(range(10))
    assert all(got[i]["points"] == {"cyan": i + 1, "magenta": i + 1} for i in range(10))

def test_address_needs_dask():
    with pytest.raises(ValueError, match="--executor dask"):
        open_executor("local", address="127.0.0.1:8786")


@pytest.mark.parametrize("argv,code,text", [
    (["htn"], 2, "at least two"),
    (["htn", "nosuchteam"], 2, "nosuchteam"),
    (["htn", "baseline", "--address", "127.0.0.1:1"], 2, "--executor dask"),
    (["htn", "baseline", "--seeds", "0"], 2, "must be >= 1"),
])
def test_usage_errors_exit_2_before_any_game(argv, code, text, tmp_path, capsys):
    with pytest.raises(SystemExit) if "--seeds" in argv else _nothing():
        rc = main(["tournament", *argv, "--out", str(tmp_path / "t")])
        assert rc == code
    assert text in capsys.readouterr().err
    assert not (tmp_path / "t" / "tournament.sqlite").exists()


def test_no_scheduler_at_the_address_exits_3(tmp_path, capsys):
    port = free_ports(1, tcp=True)[0]
    rc = main(["tournament", "htn", "baseline", "--executor", "dask", "--address", f"127.0.0.1:{port}",
               "--out", str(tmp_path / "t"), "-q"])
    assert rc == 3 and "no Dask scheduler" in capsys.readouterr().err


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
