"""``rll-bt sim --refbox external`` on the command line: a refbox that is not there
is exit code 3 with what was tried, options that cannot go with it are exit code 2."""
from __future__ import annotations

import socket

import pytest

from rll_bt.cli import main


def _closed_offset() -> int:
    """A port offset whose refbox stream port (4444 + offset) nobody listens on."""
    for off in range(21000, 30000, 37):
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", 4444 + off)) != 0:
                return off
    raise RuntimeError("no closed port found")


def test_an_unreachable_refbox_is_exit_code_3(capsys):
    off = _closed_offset()
    rc = main(["sim", "--refbox", "external", "--profile", "rcll2025", "--refbox-port-offset", str(off),
               "--refbox-timeout", "1", "-q"])
    err = capsys.readouterr().err
    assert rc == 3
    assert f"127.0.0.1:{4444 + off}" in err and "--refbox-host" in err


@pytest.mark.parametrize("extra, words", [
    (["--save-game", "g.json"], "draws its own game"),
    (["--hardware", "emulated"], "simulated refbox only"),
    (["--refbox-timeout", "0"], "refbox_timeout must be positive"),
    (["--refbox-port-offset", "70000"], "refbox_port_offset must be"),
])
def test_options_that_do_not_go_with_an_external_refbox_are_exit_code_2(extra, words, capsys):
    rc = main(["sim", "--refbox", "external", "--profile", "rcll2025", "-q", *extra])
    assert rc == 2
    assert words in capsys.readouterr().err
