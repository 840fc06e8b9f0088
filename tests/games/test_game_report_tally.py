"""The game report counts the team's stations that went BROKEN, by cause, and the referee
calls (what the real refbox leaves to a human referee), in report.json and in the table."""
from types import SimpleNamespace

from games import report
from rll_bt.contracts import Tally


def _summary(**extra) -> dict:
    return {"profile": "rcll2025", "seed": 1, "robots": 3, "strategy": "algorithm1",
            "perception": "oracle", "finished": True, "phase": "POST_GAME", "sim_time": 1500.0,
            "wall_time": 100.0, "setup_shortened": True, "phase_lengths": {"SETUP": 10.0},
            "exploration": {"points": 20, "max_points": 28, "all_points_after": None,
                            "sure_all_after": None},
            "points": {"production": 300, "total": 320}, "orders_delivered": 5, "collisions": 0,
            "collisions_by_kind": {}, "robot_stats": {}, **extra}


def test_the_tally_of_the_team_goes_into_the_report():
    t = Tally({"timeout": 2, "not-prepared": 1},
              {"dropped-workpiece": {"count": 1, "penalty": -10}})
    got = report._tally(SimpleNamespace(tally={"CYAN": t}), "CYAN")
    assert got == {"stations_broken": {"total": 3, "by_cause": {"timeout": 2, "not-prepared": 1}},
                   "referee": {"calls": {"dropped-workpiece": {"count": 1, "penalty": -10}},
                               "penalty": -10}}
    assert report._tally(SimpleNamespace(tally={}), "CYAN")["stations_broken"]["total"] == 0


def test_the_end_of_game_table_shows_broken_stations_and_referee_calls():
    s = _summary(**report._tally(SimpleNamespace(tally={"CYAN": Tally(
        {"timeout": 2}, {"obstruction": {"count": 1, "penalty": -20}})}), "CYAN"))
    lines = report.table(s).splitlines()
    assert next(x for x in lines if x.startswith("stations broken")).split()[2:] == \
        ["2", "timeout", "2"]
    assert "obstruction 1 (-20)" in next(x for x in lines if x.startswith("referee calls"))


def test_each_collision_of_the_team_goes_into_the_report():
    log = [(12.345, "CYAN/2", "C-CS1"), (13.0, "MAGENTA/1", "wall"), (20.0, "CYAN/1", "robot MAGENTA/1")]
    assert report.collisions_of(log, "CYAN") == [[12.35, "CYAN/2", "C-CS1"], [20.0, "CYAN/1", "robot MAGENTA/1"]]
    assert report.collisions_of(log, "MAGENTA") == [[13.0, "MAGENTA/1", "wall"]]
