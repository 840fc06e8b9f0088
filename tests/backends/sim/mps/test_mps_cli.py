"""``rll-bt sim stations``: exit codes a user relies on, and a stored game's field."""
from __future__ import annotations

from backends.sim.mps.broker import free_port
from backends.sim.stored import StoredGame
from rll_bt.cli import main


def test_nothing_to_serve_is_bad_usage(capsys):
    assert main(["sim", "stations", "--duration", "1"]) == 2
    assert "nothing to serve" in capsys.readouterr().err


def test_an_unreachable_broker_exits_3(capsys):
    assert main(["sim", "stations", "--mqtt", f"127.0.0.1:{free_port()}", "--duration", "1"]) == 3
    assert "unreachable" in capsys.readouterr().err


def test_serves_a_stored_games_field_through_its_own_broker(tmp_path, capsys):
    game = StoredGame("rcll2025", {"C-BS": ("C_Z44", 90), "C-RS1": ("C_Z63", 270), "M-BS": ("M_Z44", 90),
                                   "M-RS1": ("M_Z63", 270)},
                      ring_colors={"C-RS1": ("RING_BLUE", "RING_GREEN")})
    path = tmp_path / "game.json"
    game.save(str(path))
    port = free_port()
    rc = main(["sim", "stations", "--game", str(path), "--broker", "amqtt", "--mqtt", f"127.0.0.1:{port}",
               "--machines", "C-BS,C-RS1", "--duration", "0.5", "--rate", "5"])
    assert rc == 0
    assert "stations on MQTT" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("[]")
    assert main(["sim", "stations", "--game", str(bad), "--opcua", "--duration", "0.1"]) == 2


def test_sigterm_stops_the_command_and_its_broker():
    import signal
    import subprocess
    import sys
    import time

    from backends.sim.mps.broker import reachable
    port = free_port()
    script = [sys.executable, "-c", "import sys; from rll_bt.cli import main; sys.exit(main())"]
    proc = subprocess.Popen([*script, "sim", "stations", "--broker", "amqtt",
                             "--mqtt", f"127.0.0.1:{port}", "--machines", "C-BS"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not reachable("127.0.0.1", port) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert reachable("127.0.0.1", port), "the broker did not come up"
        time.sleep(1.0)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    time.sleep(0.5)
    assert not reachable("127.0.0.1", port)                     # no broker left behind
