"""``rll-bt sim``: a short game end to end, what ``--out`` holds, bad input."""
import json
import re

import cv2
import numpy as np
import pytest

from games import GameOptions, LockstepGame, progress
from rll_bt.cli import main

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out

SHORT = ["--robots", "2", "--setup", "1", "--exploration", "25", "--production", "20", "-q"]
PROGRESS = re.compile(r"\]\s+(\d+)/(\d+) s\s+([A-Z_]+)\s+(\d+) s\s+score\s+(-?\d+)")


class _EveryLine(progress.ProgressBar):
    """The progress bar with a plain line at every sample (a short game is over
    before the 15 s of a plain line elapse)."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **{**kw, "every_plain": 0.0})


def test_a_short_game_writes_the_report_the_log_and_the_pictures(tmp_path, capsys, monkeypatch):
    out = tmp_path / "game"
    monkeypatch.setattr(progress, "ProgressBar", _EveryLine)
    assert main(["sim", "--seed", "2", *[a for a in SHORT if a != "-q"], "--out", str(out)]) == 0
    captured = capsys.readouterr()
    rep = json.loads((out / "report.json").read_text())
    _table_matches_the_report(captured.out, rep)
    _progress_shows_time_phase_and_score(captured.err, rep)
    for name in ("messages.jsonl", "report.json", "field.png", "timeline.png", "score.png"):
        assert (out / name).stat().st_size > 0, name
    for name in ("field.png", "timeline.png", "score.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        img = cv2.imread(str(out / name))
        assert img is not None and img.ndim == 3, name
        h, w = img.shape[:2]
        assert 300 <= h <= 4000 and 300 <= w <= 4000, (name, img.shape)
        background = np.all(img == img[0, 0], axis=2).mean()      # the corner's colour
        assert background < 0.97, f"{name} is (nearly) blank"
        assert len(np.unique(img.reshape(-1, 3), axis=0)) > 16, f"{name} has hardly any colours"
    assert rep["finished"] and rep["phase"] == "POST_GAME"
    assert rep["points"]["total"] == rep["points"]["exploration"] + rep["points"]["production"]
    assert 0 < rep["exploration"]["points"] <= rep["exploration"]["max_points"] == 48
    assert set(rep["robot_stats"]) == {"1", "2"}
    assert all(r["busy_time"] <= rep["sim_time"] for r in rep["robot_stats"].values())
    assert rep["setup_shortened"] and rep["phase_lengths"]["SETUP"] == 1.0
    lines = [json.loads(x) for x in (out / "messages.jsonl").read_text().splitlines()]
    assert len(lines) >= rep["messages"] > 0      # + what the agents say when they shut down
    types = {x["type"] for x in lines}
    # refbox broadcasts, the encrypted team channel and the encrypted team-server link all decode
    assert {"GameState", "BeaconSignal", "MachineReport", "AgentTask", "TaskDetail", "TaskOutcome",
            "RobotStatus"} <= types
    assert all(x["type"] is not None for x in lines)
    reports = [x for x in lines if x["type"] == "MachineReport"]
    assert reports[0]["channel"] == "cyan" and reports[0]["msg"]["team_color"] == "CYAN"
    assert [x["t"] for x in lines] == sorted(x["t"] for x in lines)


def _table_matches_the_report(table: str, rep: dict) -> None:
    def row(label):
        m = re.search(rf"^{label}\s+(-?\d+)", table, re.M)
        assert m, f"no {label!r} row in\n{table}"
        return int(m.group(1))
    assert row("exploration points") == rep["exploration"]["points"]
    assert row("production points") == rep["points"]["production"]
    assert row("total score") == rep["points"]["total"]
    assert row("orders delivered") == rep["orders_delivered"]
    robots = {m.group(1): m.groups()[1:] for m in
              re.finditer(r"^R(\d+)\s+(\d+)\s+(\d+)%\s+(\d+)\s+(\d+)\s+([\d.]+)$", table, re.M)}
    assert set(robots) == set(rep["robot_stats"]) == {"1", "2"}
    for n, (busy, share, ntasks, failed, driven) in robots.items():
        r = rep["robot_stats"][n]
        assert abs(int(busy) - r["busy_time"]) <= 0.5 and r["busy_time"] > 0
        assert abs(int(share) - 100 * r["busy_share"]) <= 0.5
        assert (int(ntasks), int(failed), float(driven)) == (r["tasks"], r["failed"], r["distance"])


def _progress_shows_time_phase_and_score(err: str, rep: dict) -> None:
    lines = [tuple(int(g) if g.lstrip("-").isdigit() else g for g in m.groups())
             for m in PROGRESS.finditer(err)]
    assert len(lines) > 10, err
    total = 1 + 25 + 20
    assert all(t <= total + 1 and of == total for t, of, *_ in lines)
    assert [t for t, *_ in lines] == sorted(t for t, *_ in lines)
    phases = [p for _, _, p, _, _ in lines]
    assert {"EXPLORATION", "PRODUCTION"} <= set(phases) and phases[-1] == "POST_GAME"
    for phase, length in (("EXPLORATION", 25), ("PRODUCTION", 20)):
        times = [g for _, _, p, g, _ in lines if p == phase]
        assert times == sorted(times) and length - 2 <= times[-1] <= length, (phase, times)
    assert any(s > 0 for *_, p, _, s in lines if p == "EXPLORATION")      # the score as it grows
    assert lines[-1][4] == rep["points"]["total"]


def test_the_same_seed_plays_the_same_game():
    def play():
        with LockstepGame(GameOptions(seed=6, robots=1, setup=1, exploration=20, production=10)) as g:
            r = g.run()
            return ([(a.reason, round(a.game_time, 3)) for a in r.awards],
                    [(t["kind"], t["assigned_at"], t["finished_at"]) for t in r.snapshot["tasks"]],
                    r.recording.paths[1][-1])
    assert play() == play()


def test_bad_arguments_exit_2_and_sim_world_still_works(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--robots", "5"])
    assert exc.value.code == 2
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["sim", "--out", str(blocker / "sub"), "-q"]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["sim", "world", "--seed", "3", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["seed"] == 3


@pytest.mark.parametrize("mode", [[], ["--processes"]])
def test_gui_without_a_display_is_one_clear_line_and_exit_3(tmp_path, capsys, monkeypatch, mode):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["sim", "--gui", *mode, "-q", "--out", str(tmp_path)]) == 3
    err = capsys.readouterr().err
    assert "--gui" in err and "display" in err and "Traceback" not in err
    assert not list(tmp_path.glob("*.log"))          # no process was started
