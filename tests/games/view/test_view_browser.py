"""The live page in a real browser: headless Chromium (Debian's package,
``make browser``) over its DevTools protocol opens ``rll-bt sim --view``'s
page during a short game and sees the robots move and the score change,
the stations, the orders and the running branch of the trees; then plays
the game's recording back with ``rll-bt view``.  Screenshots are kept in
``test-output/browser/`` (``tests.support.OUTPUT``; their paths are printed)."""
from __future__ import annotations

import json
import queue
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from games import GameOptions, LockstepGame
from tests.support import OUTPUT
from tests.support.browser import Browser

pytestmark = pytest.mark.slow          # plays a game to its end

RLL_BT = str(Path(sys.executable).parent / "rll-bt")
ROBOTS = ("[...document.querySelectorAll('#robots .robot')]"
          ".map(g => [g.id, Number(g.dataset.x), Number(g.dataset.y)])")
SCORE = "document.querySelector('#score').textContent"
#: waits are for events (the page shows something); the time limits only end a test that would hang,
#: generous for a loaded 2-core machine
LONG = 300.0
KEEP = OUTPUT / "browser"


def moved(before: list, after: list) -> list[str]:
    old = {r: (x, y) for r, x, y in before}
    return [r for r, x, y in after if r in old and abs(x - old[r][0]) + abs(y - old[r][1]) > 0.3]


def _ctrl_c_stops() -> None:
    """In the child: Ctrl-C as in a terminal (a test run started in the background of a shell
    inherits SIGINT ignored, and Python then never raises KeyboardInterrupt)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _lines(stream, out: queue.Queue) -> None:
    for line in stream:
        out.put(line)


def test_the_live_page_follows_a_game_and_replays_it(tmp_path):
    KEEP.mkdir(parents=True, exist_ok=True)
    for old in KEEP.glob("*.png"):
        old.unlink()
    opts = GameOptions(seed=2, robots=2, setup=1.0, exploration=20.0, production=25.0, strategy="oracle",
                       view=0, record=tmp_path / "game.mcap", speed=0)
    game = LockstepGame(opts)
    try:
        with Browser(tmp_path / "chromium") as browser:
            game.start()
            game.run_for(1.0)
            page = browser.open(game.view.url)
            page.wait_for("document.querySelectorAll('#robots .robot').length === 2", timeout=LONG)
            assert page.eval("document.querySelector('#link').className") == "link up"   # the event stream is open
            before, score0 = page.eval(ROBOTS), page.eval(SCORE)
            assert score0 == "0" and page.eval("document.querySelector('#phase').textContent").startswith("SETUP")

            def playing_on(what: str):        # the game runs on (one game second a poll) while the page is polled
                def step():
                    assert not game.finished(), f"the game ended before the page showed {what}"
                    game.run_for(1.0)
                return step
            start = json.dumps({r: [x, y] for r, x, y in before})
            page.wait_for(f"""(() => {{ const s = {SCORE}, b = {start};
                const moved = {ROBOTS}.filter(([r, x, y]) => Math.abs(x - b[r][0]) + Math.abs(y - b[r][1]) > 0.3);
                return s !== '0' && s !== '–' && moved.length === 2; }})()""", timeout=LONG,
                          between=playing_on("both robots moved and a score"))
            after = page.eval(ROBOTS)
            assert set(moved(before, after)) == {"robot-1", "robot-2"}, (before, after)
            assert int(page.eval(SCORE)) > 0
            # the field's stations, the paths, the score chart and the trees with their running branch
            assert page.eval("document.querySelectorAll('#stations .station').length") == 12
            assert page.eval("document.querySelector('#station-C-BS').getAttribute('class')") == "station CYAN"
            assert page.eval("document.querySelectorAll('#paths .path').length") == 2
            assert page.eval("document.querySelector('#score-chart polyline').getAttribute('points').split(' ')"
                             ".length") >= 2
            page.wait_for("document.querySelectorAll('#trees .node.running').length > 0", timeout=LONG,
                          between=playing_on("a running tree node"))
            running = page.eval("[...document.querySelectorAll('#trees .node.running')].map(n => n.textContent)")
            assert running and page.eval("document.querySelectorAll('#trees .tree').length") == 2
            # production: the orders with their delivery windows
            page.wait_for("document.querySelectorAll('#orders tbody tr').length > 0", timeout=LONG,
                          between=playing_on("an order"))
            assert page.eval("document.querySelectorAll('#orders tbody .window .span').length") > 0
            shot = page.screenshot(KEEP / "live-view.png")
            print(f"\nscreenshot of the live page: {shot}")
            assert shot.stat().st_size > 20_000
            result = game.run()
            page.wait_for("document.querySelector('#result').textContent.includes('game over')", timeout=LONG)
        final = result.status.points["CYAN"]
    finally:
        game.close()

    # the recording, played back by rll-bt view at 20 times real time: it starts paused, the page seeks
    # to the first second, reads where the robots are and presses play
    view = subprocess.Popen([RLL_BT, "view", str(tmp_path / "game.mcap"), "--port", "0", "--speed", "20",
                             "--paused"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL, preexec_fn=_ctrl_c_stops)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=_lines, args=(view.stderr, lines), daemon=True).start()
    try:
        url, said = None, []
        while url is None:
            line = lines.get(timeout=LONG)
            said.append(line)
            m = re.search(r"open (http://\S+) in a browser", line)
            url = m.group(1) if m else None
            assert view.poll() is None, f"rll-bt view exited ({view.returncode}): {''.join(said)}"
        with Browser(tmp_path / "chromium-replay") as browser:
            page = browser.open(url)
            page.wait_for("!document.querySelector('#playback').hidden", timeout=LONG)
            assert page.eval("document.querySelector('#play').textContent") == "▶"          # paused
            page.eval("(() => { const s = document.querySelector('#seek'); s.value = Number(s.min) + 1; "
                      "s.dispatchEvent(new Event('change')); return true; })()")
            page.wait_for("Number(document.querySelector('#seek').value) >= Number(document.querySelector('#seek')"
                          ".min) + 0.95 && document.querySelectorAll('#robots .robot').length === 2", timeout=LONG)
            first = page.eval(ROBOTS)
            page.eval("document.querySelector('#play').click() || true")
            page.wait_for("document.querySelector('#result').textContent.includes('game over')", timeout=LONG)
            assert set(moved(first, page.eval(ROBOTS))) == {"robot-1", "robot-2"}, first
            assert page.eval(SCORE) == str(final)
            shot = page.screenshot(KEEP / "replay-view.png")
            print(f"screenshot of the replay: {shot}")
    finally:
        view.send_signal(signal.SIGINT)                   # Ctrl-C
        try:
            rc = view.wait(60)
        finally:
            if view.poll() is None:
                view.kill()
                view.wait()
    assert rc == 130, "".join(said)
