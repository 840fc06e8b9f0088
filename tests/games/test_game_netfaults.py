"""Games on a lossy radio: ``--net-*`` faults on every robot's team-server link."""
import pytest

from games import GameOptions, LockstepGame
from rll_bt.cli import main
from rll_bt.comm.faults import FaultyTransport, NetFaults


@pytest.mark.parametrize("bad", [["--net-loss", "1.5"], ["--net-loss", "x"], ["--net-delay", "-1"],
                                 ["--net-cut", "R1:9-3"], ["--net-cut", "R1"]])
def test_bad_network_faults_are_bad_usage(bad, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sim", "-q", *bad])
    assert exc.value.code == 2
    assert "--net-" in capsys.readouterr().err


def test_a_cut_of_no_robot_is_bad_usage(capsys):
    assert main(["sim", "-q", "--net-cut", "robot:1-3"]) == 2
    assert "R<N>" in capsys.readouterr().err


def test_the_help_says_which_links_the_faults_are_on(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--help"])
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "link to the team server" in text and "refbox's channels stay perfect" in text


def _counts(net: NetFaults, seconds: float):
    opts = GameOptions(seed=6, robots=2, setup=1.0, exploration=30.0, production=30.0, strategy="oracle", net=net)
    with LockstepGame(opts) as game:
        cut = []

        def watch(g):
            if 12.0 <= g.clock.now() < 25.0:
                cut.append(g.teamserver.snapshot()["robots"][1]["status"])
        game.hooks.append(watch)
        game.run_for(seconds)
        links = {n: a.link for n, a in game.agents.items()}
        assert all(isinstance(x, FaultyTransport) for x in links.values())
        return ({n: dict(x.counts) for n, x in links.items()}, {n: a.registrations for n, a in game.agents.items()},
                game.teamserver.snapshot()["robots"], cut)


@pytest.mark.slow
def test_a_lockstep_game_on_a_lossy_radio_is_deterministic_and_a_cut_robot_comes_back():
    # R1 cut longer than its lease (10 s and the lag it measured, 3-4 s at 1 s each way)
    net = NetFaults(loss=0.2, delay=1.0, jitter=0.2, cuts=(("R1", 5.0, 25.0),))
    counts, registrations, robots, cut = _counts(net, 32.0)
    assert counts[1]["retransmitted_out"] > 0 and counts[2]["retransmitted_in"] > 0 and counts[1]["cut_in"] > 0
    assert "cut_in" not in counts[2]                    # only R1 was cut
    assert registrations == {1: 2, 2: 1}                # R1 said hello again after the cut
    assert "LOST" in cut                                # the team server noticed the silent robot ...
    assert robots[1]["status"] == "ACTIVE"              # ... and took it back
    assert _counts(net, 32.0)[0] == counts              # the same seed, the same faults
