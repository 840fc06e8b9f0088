"""A game saved (``--save-game``) and played again from the file (``--game``)
is the same game: the same report and the same messages, byte for byte, in
lockstep.  And the file, not the seed, decides: played with another seed it
keeps the stored field and orders."""
from __future__ import annotations

import json

import pytest

from games import GameOptions, LockstepGame, finish

pytestmark = [pytest.mark.slow,  # whole games: `make test-fast` leaves them out
              pytest.mark.timeout(1500)]  # two 2025 games: more than 300 s at a load of 45 on 2 cores

SHORT = {"profile": "rcll2025", "setup": 1.0, "exploration": 40.0, "production": 60.0, "strategy": "oracle"}


def _play(out, **kw):
    options = GameOptions(**{**SHORT, **kw, "out": out})
    with LockstepGame(options) as game:
        result = game.run()
        summary = finish(result, options)
        stations = {n: (s.zone, s.rotation, s.pose) for n, s in game.refbox.stations().items()}
        orders = game.refbox.orders()
    summary.pop("wall_time")
    summary.pop("table")
    return summary, (out / "messages.jsonl").read_bytes(), stations, orders


def test_a_game_saved_and_loaded_plays_identically(tmp_path):
    stored = tmp_path / "game.json"
    first = _play(tmp_path / "first", seed=4, save_game=stored)
    again = _play(tmp_path / "again", seed=4, game=stored)
    assert json.loads(stored.read_text())["format"] == "rll-bt stored game"
    assert first[0]["finished"] and first[0]["points"]["total"] > 0
    assert again[0] == first[0]                       # the same report
    assert again[1] == first[1]                       # the same messages, byte for byte
    assert again[2:] == first[2:]


def test_the_stored_game_not_the_seed_decides_field_and_orders(tmp_path):
    stored = tmp_path / "game.json"
    seed4 = _play(tmp_path / "seed4", seed=4, save_game=stored, production=5.0)
    other = _play(tmp_path / "seed7", seed=7, production=5.0)
    seed7_on_4 = _play(tmp_path / "seed7-on-4", seed=7, game=stored, production=5.0)
    assert other[2] != seed4[2] and other[3] != seed4[3]     # seed 7 draws its own game ...
    assert seed7_on_4[2] == seed4[2]                          # ... but plays the stored field
    assert seed7_on_4[3] == seed4[3]                          # ... and orders
