"""The storage station in a whole lockstep rcll2025 game: the simulated refbox, the
PyBullet world, the team server and three agents running the put/get trees at C-SS.

A 540 s production is too short for a product to be ready long before its window,
so the team server is told to store every product (``min_wait`` -inf): what is
checked is the machinery on the wire and in the world, not when storing pays
(tests/teamserver/production/test_ts_storage.py)."""
import json
import math

import pytest

from games import GameOptions, LockstepGame
from teamserver.dispatch import DispatchConfig
from teamserver.planning.planner import StoragePolicy

pytestmark = pytest.mark.slow  # whole games: `make test-fast` leaves them out


def test_a_product_goes_through_the_storage_station_and_is_delivered(tmp_path):
    opts = GameOptions(profile="rcll2025", seed=3, setup=1.0, exploration=40.0, production=540.0,
                       strategy="oracle", out=tmp_path,
                       extra={"dispatch": DispatchConfig(heartbeat_timeout=3.0),
                              "storage": StoragePolicy(min_wait=-math.inf)})
    game = LockstepGame(opts)
    try:
        result = game.run()
    finally:
        game.close()
    assert result.finished
    prepares = []
    for line in (tmp_path / "messages.jsonl").read_text(encoding="utf-8").splitlines():
        if '"PrepareMachine"' in line:
            m = json.loads(line)
            assert m["channel"] == "cyan" and m["from"] == "teamserver"
            prepares.append((m["t"], m["msg"]["machine"], m["msg"]))
    ss = [(t, m["instruction_ss"]) for t, name, m in prepares if name == "C-SS"]
    assert [i["operation"] for _, i in ss][:2] == ["STORE", "RETRIEVE"]
    (t_store, store), (t_get, get) = ss[:2]
    assert (store["shelf"], store["slot"]) == (get["shelf"], get["slot"]) and t_store < t_get
    # the retrieved product is delivered for its order, and scored (storing is forced here
    # whatever the window, so it may come late: 2025 grades a late delivery, it still pays)
    ds = [(t, m["instruction_ds"]["order_id"]) for t, name, m in prepares if name == "C-DS"]
    t_ds, oid = next((t, o) for t, o in ds if t > t_get)
    [d] = [d for d in result.deliveries if d.order == oid and d.team == "CYAN"]
    assert d.how in ("in-time", "late") and d.points > 0
    # by the robots' trees: a put into the SS input and a pickup from its output
    tasks = result.snapshot["tasks"]
    assert {(t["kind"], t["state"]) for t in tasks if t["machine"] == "C-SS"} >= {
        ("put_workpiece", "DONE"), ("get_workpiece", "DONE")}
