"""``rll-bt agent --localisation PRESET``: the localiser preset the agent's skills
build, as ``rll-bt sim --processes`` passes its own ``--localisation`` on."""
import socket

import pytest

import rll_bt.agent
from games.options import published
from rll_bt.cli import main
from skills.localisation.config import AmclConfig

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _args(*extra):
    return ["agent", "--robot", "1", "--team", "GRIPS", "--key", "somekey", "--backend", "scripted",
            "--teamserver", f"127.0.0.1:{_free_port()}", "--no-refbox", "--seconds", "0.3", "-q", *extra]


@pytest.fixture
def made(monkeypatch):
    """The services every RobotAgent made by the CLI got."""
    seen = []

    class Recording(rll_bt.agent.RobotAgent):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            seen.append(dict(self.services))
    monkeypatch.setattr(rll_bt.agent, "RobotAgent", Recording)
    return seen


@pytest.mark.parametrize("preset", published("localisation"))
def test_the_preset_reaches_the_agents_skills(made, preset):
    assert main(_args("--localisation", preset)) == 0
    assert made[-1]["localisation"] == preset
    AmclConfig.preset(preset)                 # a preset the localiser knows


def test_a_real_robot_gets_the_accurate_localiser_by_default(made):
    assert main(_args()) == 0
    assert made[-1]["localisation"] == "standard"


def test_an_unknown_preset_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        main(_args("--localisation", "fast"))
    assert exc.value.code == 2
    assert "--localisation" in capsys.readouterr().err


def test_the_processes_game_starts_its_agents_with_the_games_preset(tmp_path, monkeypatch):
    from games import GameOptions
    from games.processes import ProcessGame
    cmds = {}
    monkeypatch.setattr(ProcessGame, "_spawn", lambda self, name, cmd: cmds.__setitem__(name, cmd))
    monkeypatch.setattr(ProcessGame, "_wait_for", lambda self, ready, what: None)    # no refbox to wait for
    game = ProcessGame(GameOptions(robots=2, processes=True, localisation="standard", out=tmp_path))
    try:
        for n in (1, 2):
            cmd = cmds[f"agent{n}"]
            assert cmd[cmd.index("--localisation") + 1] == "standard"
    finally:
        game.close()
    assert GameOptions().localisation == "cheap"
    with pytest.raises(ValueError, match="localisation"):
        GameOptions(localisation="fast")
