"""``rll-bt sim``: a short game end to end, what ``--out`` holds, bad input."""
import json

import pytest

from rll_bt.cli import main
from rll_bt.game import GameOptions, LockstepGame

SHORT = ["--robots", "2", "--setup", "1", "--exploration", "25", "--production", "20", "-q"]


def test_a_short_game_writes_the_report_the_log_and_the_pictures(tmp_path, capsys):
    out = tmp_path / "game"
    assert main(["sim", "--seed", "2", *SHORT, "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "exploration points" in table and "R2" in table
    for name in ("messages.jsonl", "report.json", "field.png", "timeline.png", "score.png"):
        assert (out / name).stat().st_size > 0, name
    for name in ("field.png", "timeline.png", "score.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rep = json.loads((out / "report.json").read_text())
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
    assert {"GameState", "BeaconSignal", "MachineReport", "Task", "TaskResult", "RobotStatus"} <= types
    assert all(x["type"] is not None for x in lines)
    reports = [x for x in lines if x["type"] == "MachineReport"]
    assert reports[0]["channel"] == "cyan" and reports[0]["msg"]["team_color"] == "CYAN"
    assert [x["t"] for x in lines] == sorted(x["t"] for x in lines)


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
