"""``--view``, ``--live`` and ``--speed`` of ``rll-bt sim``: the pace a watched
game keeps, and bad input."""
from __future__ import annotations

import socket
import time

import pytest

from games import GameOptions, LockstepGame
from rll_bt.cli import main
from rll_bt.clock import WallClock


def test_a_watched_game_keeps_to_real_time_unless_told_otherwise():
    assert GameOptions().pace == 0.0                        # as fast as the machine goes
    assert GameOptions(live=0).pace == GameOptions(view=0).pace == GameOptions(gui=True).pace == 1.0
    assert GameOptions(view=0, speed=0).pace == 0.0 and GameOptions(speed=5).pace == 5.0
    with pytest.raises(ValueError):
        GameOptions(speed=-1)


def test_speed_paces_the_game():
    with LockstepGame(GameOptions(robots=1, setup=1.0, speed=4.0), pace=WallClock()) as game:
        game.start()
        t0 = time.monotonic()
        game.run_for(2.0)                                   # 2 game seconds at 4x: at least half a second
        assert time.monotonic() - t0 >= 0.45


@pytest.mark.parametrize("args", [["--processes", "--view"], ["--processes", "--live"], ["--view", "70000"],
                                  ["--live", "-1"]])
def test_bad_watching_options_are_usage_errors(args, capsys):
    assert main(["sim", "-q", *args]) == 2
    assert "--" in capsys.readouterr().err


def test_a_view_port_that_is_taken_exits_3(capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["sim", "-q", "--robots", "1", "--view", str(port)]) == 3
    assert f"--view {port}" in capsys.readouterr().err
