"""Stored games: rll-bt's JSON round trip, the refbox's archive of game
reports (written here in MongoDB's archive format from hand-made reports,
with the refbox's key names), the world built from a stored field, and bad
input."""
from __future__ import annotations

import gzip
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from backends.sim.stored import ArchiveError, StoredGame, StoredGameError, game_reports, load_game, read_refbox_games
from tests.support.refbox_archive import MAGIC, archive, report


def test_refbox_reports_are_read_into_stored_games(tmp_path):
    path = tmp_path / "games.gz"
    path.write_bytes(archive([report("benchmark_1"), report("benchmark_2", "C_Z24", 180)]))
    games = read_refbox_games(str(path))
    assert [g.name for g in games] == ["benchmark_1", "benchmark_2"]
    g = games[0]
    assert g.machines == {"C-BS": ("C_Z44", 90), "C-RS1": ("C_Z63", 90), "M-RS1": ("M_Z63", 90)}
    assert games[1].machines["C-RS1"] == ("C_Z24", 180)
    assert g.ring_costs == {"RING_GREEN": 2, "RING_BLUE": 1, "RING_ORANGE": 0, "RING_YELLOW": 0}
    assert g.ring_colors["C-RS1"] == ("RING_BLUE", "RING_GREEN")
    assert g.down_periods == {"C-RS1": (300.0, 345.0), "M-RS1": (300.0, 345.0)}
    c2 = g.orders[1]
    assert (c2.id, c2.complexity, c2.base, c2.rings, c2.cap, c2.delivery, c2.gate, c2.activate_at,
            c2.competitive) == (6, "C2", "BASE_RED", ("RING_BLUE", "RING_GREEN"), "CAP_BLACK", (401, 574), 3,
                                172, True)
    assert len(game_reports(archive([report("x")], zipped=False))) == 1
    assert load_game(str(path)) == g                        # an archive path loads its first game


def test_a_game_saved_and_loaded_is_the_same_game_and_the_same_field(tmp_path):
    from backends.sim import World
    original = read_refbox_games(archive([report("benchmark_1")]))[0]
    path = tmp_path / "game.json"
    original.save(str(path))
    loaded = load_game(str(path))
    assert loaded == original
    worlds = [World("rcll2025", seed=5, layout=g.layout()) for g in (original, loaded)]
    try:
        for m in original.machines:
            a, b = (w.station(m) for w in worlds)
            assert (a.zone, a.rotation, a.pose) == (b.zone, b.rotation, b.pose)
        rs = worlds[0].station("C-RS1")
        assert worlds[0].profile.zone_name(rs.zone) == "C_Z63" and rs.rotation == 90
        assert (rs.pose.x, rs.pose.y) == (5.5, 2.5)              # the zone's centre
    finally:
        for w in worlds:
            w.close()


@pytest.mark.parametrize("data, words", [
    (b"", "no magic"),
    (b"not an archive at all", "no magic"),
    (MAGIC + b"\x05\x00", "truncated"),
    (MAGIC + struct.pack("<i", 9999) + b"x" * 20, "bad document length"),
    (gzip.compress(b"x", mtime=0)[:-4], "gzip"),
])
def test_broken_archives_say_what_is_wrong(data, words):
    with pytest.raises(ArchiveError, match=words):
        game_reports(data)


def test_broken_json_and_impossible_games_say_what_is_wrong(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(StoredGameError, match="not JSON"):
        load_game(str(bad))
    bad.write_text('{"format": "something else"}')
    with pytest.raises(StoredGameError, match="not an rll-bt stored game"):
        load_game(str(bad))
    with pytest.raises(StoredGameError, match="unknown zone"):
        read_refbox_games(archive([report("x", rs1_zone="C_Z99")]))
    with pytest.raises(StoredGameError, match="malformed"):
        read_refbox_games(archive([{"report-name": "y", "machines": [{"name": "C-BS"}]}]))
    with pytest.raises(StoredGameError, match="No such file"):
        load_game(str(tmp_path / "missing.json"))


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_the_archive_reader_never_fails_other_than_clearly(tail):
    good = archive([report("z")], zipped=False)
    for data in (MAGIC + tail, good[:len(tail) % len(good)] + tail):
        try:
            games = read_refbox_games(data)
        except StoredGameError:
            continue
        assert all(isinstance(g, StoredGame) for g in games)


def test_the_field_a_refbox_announces_becomes_the_worlds():
    from rll_bt import msgs
    ms = msgs.message_set("rcll2025")
    info = ms.MachineInfo(machines=[
        ms.Machine(name="C-RS1", type="RS", zone=ms.enum("Zone").Value("C_Z63"), rotation=270,
                   ring_colors=[ms.enum("RingColor").Value("RING_ORANGE"), ms.enum("RingColor").Value("RING_GREEN")]),
        ms.Machine(name="M-BS", type="BS", zone=ms.enum("Zone").Value("M_Z44"), rotation=45),
        ms.Machine(name="C-BS", type="BS"),                   # not announced yet
    ])
    game = StoredGame.from_machine_info(info)
    assert game.machines == {"C-RS1": ("C_Z63", 270), "M-BS": ("M_Z44", 45)}
    assert game.ring_colors == {"C-RS1": ("RING_ORANGE", "RING_GREEN")}
    layout = game.layout()
    assert layout["M-BS"].rotation_deg == 45 and layout["C-RS1"].zone == 63
