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
    for opt in ("--external-team", "--teamserver", "--team-cyan", "--key-magenta", "--connect-timeout"):
        assert opt in out
