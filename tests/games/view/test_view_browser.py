"""The live page in a real browser: headless Chromium (Debian's package,
``make browser``) over its DevTools protocol opens ``rll-bt sim --view``'s
page during a short game and sees the robots move and the score change,
the stations, the orders and the running branch of the trees; then plays
the game's recording back with ``rll-bt view``.  Screenshots are kept in the
test's output directory (their paths are printed)."""
from __future__ import annotations

import json
import socket
import threading

import pytest

from games import GameOptions, LockstepGame
from rll_bt.cli import main
from tests.support.browser import Browser

pytestmark = pytest.mark.slow          # plays a game

ROBOTS = ("[...document.querySelectorAll('#robots .robot')]"
          ".map(g => [g.id, Number(g.dataset.x), Number(g.dataset.y)])")
SCORE = "document.querySelector('#score').textContent"


def moved(before: list, after: list) -> list[str]:
    old = {r: (x, y) for r, x, y in before}
    return [r for r, x, y in after if r in old and abs(x - old[r][0]) + abs(y - old[r][1]) > 0.3]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_live_page_follows_a_game_and_replays_it(tmp_path):
    opts = GameOptions(seed=2, robots=2, setup=1.0, exploration=20.0, production=25.0, strategy="oracle",
                       view=0, record=tmp_path / "game.mcap", speed=0)
    game = LockstepGame(opts)
    try:
        with Browser(tmp_path / "chromium") as browser:
            game.start()
            game.run_for(1.0)
            page = browser.open(game.view.url)
            page.wait_for("document.querySelectorAll('#robots .robot').length === 2")
            assert page.eval("document.querySelector('#link').className") == "link up"   # the event stream is open
            before, score0 = page.eval(ROBOTS), page.eval(SCORE)
            assert score0 == "0" and page.eval("document.querySelector('#phase').textContent").startswith("SETUP")

            def playing_on():                 # the game runs on while the page is polled
                game.run_for(1.0)
            start = json.dumps({r: [x, y] for r, x, y in before})
            page.wait_for(f"""(() => {{ const s = {SCORE}, b = {start};
                const moved = {ROBOTS}.filter(([r, x, y]) => Math.abs(x - b[r][0]) + Math.abs(y - b[r][1]) > 0.3);
                return s !== '0' && s !== '–' && moved.length === 2; }})()""", timeout=120, between=playing_on)
            after = page.eval(ROBOTS)
            assert set(moved(before, after)) == {"robot-1", "robot-2"}, (before, after)
            assert int(page.eval(SCORE)) > 0
            # the field's stations, the paths, the score chart and the trees with their running branch
            assert page.eval("document.querySelectorAll('#stations .station').length") == 12
            assert page.eval("document.querySelector('#station-C-BS').getAttribute('class')") == "station CYAN"
            assert page.eval("document.querySelectorAll('#paths .path').length") == 2
            assert page.eval("document.querySelector('#score-chart polyline').getAttribute('points').split(' ')"
                             ".length") >= 2
            page.wait_for("document.querySelectorAll('#trees .node.running').length > 0", between=playing_on)
            running = page.eval("[...document.querySelectorAll('#trees .node.running')].map(n => n.textContent)")
            assert running and page.eval("document.querySelectorAll('#trees .tree').length") == 2
            # production: the orders with their delivery windows
            page.wait_for("document.querySelectorAll('#orders tbody tr').length > 0", timeout=120, between=playing_on)
            assert page.eval("document.querySelectorAll('#orders tbody .window .span').length") > 0
            shot = page.screenshot(tmp_path / "live-view.png")
            print(f"\nscreenshot of the live page: {shot}")
            assert shot.stat().st_size > 20_000
            result = game.run()
            page.wait_for("document.querySelector('#result').textContent.includes('game over')",
                          between=lambda: game.watch.result(result))
        final = result.status.points["CYAN"]
    finally:
        game.close()

    # the recording, played back by rll-bt view at 20 times real time
    port = free_port()
    rc = {}
    th = threading.Thread(target=lambda: rc.setdefault("rc", main(
        ["view", str(tmp_path / "game.mcap"), "--port", str(port), "--speed", "20", "--seconds", "25"])))
    th.start()
    try:
        with Browser(tmp_path / "chromium-replay") as browser:
            page = browser.open(f"http://127.0.0.1:{port}/")
            page.wait_for("!document.querySelector('#playback').hidden && "
                          "document.querySelectorAll('#robots .robot').length === 2")
            first = page.eval(ROBOTS)
            page.wait_for("document.querySelector('#result').textContent.includes('game over')", timeout=20)
            assert set(moved(first, page.eval(ROBOTS))) == {"robot-1", "robot-2"}
            assert page.eval(SCORE) == str(final)
            shot = page.screenshot(tmp_path / "replay-view.png")
            print(f"screenshot of the replay: {shot}")
    finally:
        th.join(40)
    assert rc.get("rc") == 0
