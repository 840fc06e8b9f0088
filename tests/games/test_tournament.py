"""``rll-bt tournament``: the round robin played on the local pool, on a Dask
cluster of a scheduler and two workers started on loopback (the same rows),
and killed half-way then resumed (the same table)."""
from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from games.tournament import run_tournament
from games.tournament.play import game_part
from rll_bt.cli import main
from rll_bt.comm.ports import free_ports

pytestmark = [pytest.mark.slow,  # whole games: `make test-fast` leaves them out
              pytest.mark.xdist_group("tournament")]   # one worker builds the module's games once

CONFIGS = ["htn", "baseline"]
#: short games of one robot a team: exploration and the first production seconds
GAME = {"robots": 1, "setup": 1.0, "exploration": 15.0, "production": 15.0, "overtime": 0.0}
ARGS = ["--robots", "1", "--setup", "1", "--exploration", "15", "--production", "15", "--overtime", "0",
        "--seeds", "1", "-q"]
BIN = Path(sys.executable).parent


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    return run_tournament(CONFIGS, [1], out, jobs=2, **GAME)


def test_the_local_pool_plays_both_colours_and_writes_the_table(local):
    rows = local["rows"]
    assert local["played"] == 2 and not local["failed"]
    assert {(r["cyan"], r["magenta"], r["seed"]) for r in rows} == {("htn", "baseline", 1), ("baseline", "htn", 1)}
    for r in rows:
        assert r["finished"] and r["points"]["cyan"] > 0 and r["points"]["magenta"] > 0, r
        assert r["collisions_between_teams"] == 0, r
        assert r["pid"] != os.getpid()                          # played in a worker process
    st = {s["config"]: s for s in local["standings"]}
    for c in CONFIGS:
        mine = [r["points"][k] for r in rows for k in ("cyan", "magenta") if r[k] == c]
        theirs = [r["points"][k] for r in rows for k in ("cyan", "magenta") if r[k] != c]
        assert st[c]["games"] == 2 and st[c]["points_for"] == sum(mine)
        assert st[c]["points_against"] == sum(theirs)
        assert st[c]["best"]["points"] == max(mine)
        assert st[c]["wins"] == sum(r["winner"] == c for r in rows)
        assert st[c]["losses"] == sum(r["winner"] not in (c, None) for r in rows)


def _dask(*args, log: Path) -> subprocess.Popen:
    return subprocess.Popen([str(BIN / "dask"), *args], stdout=log.open("w"), stderr=subprocess.STDOUT,
                            start_new_session=True)


def test_a_dask_cluster_on_loopback_gives_the_local_pools_rows(local, tmp_path, capsys):
    from distributed import Client
    port = free_ports(1, tcp=True)[0]
    address = f"127.0.0.1:{port}"
    procs = [_dask("scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard",
                   log=tmp_path / "scheduler.log")]
    try:
        for i in (1, 2):
            procs.append(_dask("worker", f"tcp://{address}", "--nthreads", "1", "--no-nanny", "--no-dashboard",
                               "--name", f"w{i}", "--local-directory", str(tmp_path / f"w{i}"),
                               log=tmp_path / f"worker{i}.log"))
        with Client(f"tcp://{address}", timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        rc = main(["tournament", *CONFIGS, *ARGS, "--executor", "dask", "--address", address,
                   "--out", str(tmp_path / "dask")])
        out = capsys.readouterr().out
        assert rc == 0, out
        db = sqlite3.connect(tmp_path / "dask" / "tournament.sqlite")
        rows = {k: json.loads(v) for k, v in db.execute("SELECT key, row FROM games")}
        db.close()
        local_rows = {r["key"]: r for r in local["rows"]}
        assert set(rows) == set(local_rows)
        for k, r in rows.items():
            assert game_part(r) == game_part(local_rows[k]), k       # the same game, run elsewhere
        workers = {p.pid for p in procs[1:]}
        assert {r["pid"] for r in rows.values()} <= workers           # played by the cluster's workers
        assert out.startswith(local["table"].splitlines()[0])
        assert local["table"] in out
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()


def test_a_killed_tournament_resumes_and_gives_the_same_table(local, tmp_path):
    out = tmp_path / "tour"
    cmd = [str(BIN / "rll-bt"), "tournament", *CONFIGS, *ARGS, "--jobs", "1", "--out", str(out)]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline:
            if (out / "tournament.sqlite").exists():
                db = sqlite3.connect(out / "tournament.sqlite", timeout=30)
                try:
                    n = db.execute("SELECT COUNT(*) FROM games").fetchone()[0]
                except sqlite3.OperationalError:
                    n = 0
                db.close()
                if n >= 1:
                    break
            assert p.poll() is None, "the tournament ended before it was killed"
            time.sleep(0.2)
        else:
            pytest.fail("no game finished in 600 s")
        os.killpg(p.pid, signal.SIGKILL)           # the command and its pool, mid-way through game 2
        p.wait()
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    resumed = run_tournament(CONFIGS, [1], out, jobs=1, **GAME)
    assert resumed["played"] == 1                  # only the game the kill interrupted
    assert resumed["table"] == local["table"]
    assert [game_part(r) for r in sorted(resumed["rows"], key=lambda r: r["key"])] == \
        [game_part(r) for r in sorted(local["rows"], key=lambda r: r["key"])]
    assert (out / "scores.png").stat().st_size > 0
    assert (out / "games.csv").read_text().count("\n") == 3      # header and two games
