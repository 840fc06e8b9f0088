"""The process game's recording (games/procwatch.py): what a game recorded in memory
is what reading its MCAP file gives back."""
from dataclasses import dataclass, field
from types import SimpleNamespace

from games.procwatch import _game_topics, _Merged
from games.recorder import Recording
from games.replay import read


@dataclass
class _Status:
    phase: str = "PRODUCTION"
    points: dict = field(default_factory=lambda: {"CYAN": 12})


def test_a_station_change_at_the_time_of_two_samples_is_read_back_once(tmp_path):
    """The game's last sample (taken when the result is made) can fall on the time of the
    periodic sample before it; a station that changed then was read back twice."""
    rec = Recording()
    for t in (0.0, 1.0, 2.0, 2.0):              # the result's sample at the time of the last one
        rec.samples.append({"t": t, "phase": "PRODUCTION", "game_time": t, "points": 12})
        rec.paths.setdefault(1, []).append((t, 1.0, 2.0))
    rec.phases.append((0.0, "PRODUCTION"))
    rec.stations = {"C-CS1": [(0.0, "IDLE"), (2.0, "PREPARED")], "C-BS": [(0.0, "IDLE"), (1.0, "DOWN")]}
    rec.events.append({"t": 1.0, "what": "station down", "machine": "C-BS", "seconds": 5.0})
    result = SimpleNamespace(recording=rec, stations={}, sim_time=2.0, finished=True, status=_Status(),
                             collisions=0, messages={}, collision_log=[], snapshot={}, orders=[], awards=[],
                             deliveries=[])
    out = _Merged(tmp_path / "game.mcap", 10**18, {"team": "CYAN"})
    _game_topics(out, result, "rcll2016")
    out.close()
    rep = read(tmp_path / "game.mcap")
    assert rep.recording.stations == rec.stations
    assert rep.recording == rec
