"""``kill PID`` of a running game (``rll-bt sim``, a benchmark) closes the game
like Ctrl-C: whatever processes it started are stopped, and ``rll-bt sim``
exits 130.  Before, SIGTERM ended only the game's own process, and the team
server, the agents and the device emulators of a ``--processes`` or
``--hardware emulated`` game ran on without a parent."""
import signal
import subprocess
import sys
import textwrap
import time

SCRIPT = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    import games
    from rll_bt.cli import main

    mark = Path(sys.argv[1])

    class Game:                        # stands for a game that started processes
        watch = view = None

        def __init__(self, options, progress=None, pace=None):
            pass

        def run(self):
            mark.write_text("running")
            time.sleep(60)

        def close(self):
            mark.write_text("closed")  # ProcessGame.close stops its children here

    games.LockstepGame = Game
    sys.exit(main(["sim", "--seed", "1", "-q"]))
""")


def test_sigterm_closes_the_game_and_exits_130(tmp_path):
    mark = tmp_path / "mark"
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, str(mark)], stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not (mark.exists() and mark.read_text() == "running"):
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < deadline, "the game never started"
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert rc == 130, proc.stderr.read()
    assert mark.read_text() == "closed"
