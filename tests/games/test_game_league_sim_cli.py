"""``rll-bt sim --external-team`` on the command line: what it refuses before a
world is built (exit 2, naming the option), and its help."""
from __future__ import annotations

import pytest

from rll_bt.cli import main


@pytest.mark.parametrize("argv, where", [
    (["--teamserver", "127.0.0.1:2016"], "--teamserver"),                               # no external team
    (["--external-team", "cyan", "--external-team", "cyan"], "--external-team"),         # a colour twice
    (["--external-team", "cyan", "--teamserver", "127.0.0.1:1", "--teamserver", "127.0.0.1:2"], "--teamserver"),
    (["--external-team", "cyan", "--key-cyan", ""], "--key-cyan"),                       # no key
    (["--external-team", "cyan", "--speed", "0"], "--speed"),                            # not on the wall clock
    (["--external-team", "cyan", "--refbox-port-offset", "61000"], "--refbox-port-offset"),   # past port 65535
])
def test_bad_usage_is_exit_2_naming_the_option(argv, where, capsys):
    assert main(["sim", *argv]) == 2
    assert where in capsys.readouterr().err


def test_a_team_server_address_must_be_host_and_port(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--external-team", "cyan", "--teamserver", "127.0.0.1:notaport"])
    assert exc.value.code == 2 and "HOST:PORT" in capsys.readouterr().err


def test_help_names_the_external_team_options(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--help"])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    for opt in ("--external-team", "--teamserver", "--team-cyan", "--key-magenta", "--connect-timeout",
                "--refbox-port-offset"):
        assert opt in out


class _Wall:
    """A wall clock that moves only when slept on."""

    def __init__(self):
        self.t = 0.0

    def now(self) -> float:
        return self.t

    def epoch(self) -> float:
        return 1.7e9 + self.t

    def sleep(self, seconds: float) -> None:
        self.t += max(0.0, seconds)


def test_the_league_simulator_runs_speed_times_faster_than_the_wall_clock():
    from games.league_sim import ExternalGame, ExternalTeam
    from rll_bt.comm import Layout, PeerPorts, free_ports
    p = free_ports(7)
    layout = Layout("test", public=PeerPorts(send=p[0], recv=p[1]), cyan=PeerPorts(send=p[2], recv=p[3]),
                    magenta=PeerPorts(send=p[4], recv=p[5]), stream=-1)
    wall = _Wall()
    # nobody listens at p[6]: the robot keeps trying to connect while the world runs
    with ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", p[6]), "Leaguers", "league-key", robots=1)],
                      seed=1, layout=layout, wall=wall, speed=3.0) as game:
        t0 = game.clock.now()
        game.run_until(lambda g: False, 3.0)
        assert game.clock.now() - t0 >= 3.0
        assert (game.clock.now() - t0) / wall.t == pytest.approx(3.0, rel=0.02)
    with pytest.raises(ValueError, match="speed"):
        ExternalGame([ExternalTeam("CYAN", ("127.0.0.1", p[6]), "Leaguers", "league-key")], speed=0.0)
