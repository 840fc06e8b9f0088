"""The team server's store stays bounded: observations are folded into the beliefs'
votes past a limit, and nothing a decision reads changes, live or after a restart."""
import random

import pytest

from rll_bt import rules
from teamserver.knowledge import model as M
from teamserver.knowledge.kb import REFBOX, KnowledgeBase
from teamserver.knowledge.store import WAL_LIMIT, Store

P16 = rules.profile("rcll2016")
MACHINES = ("C-CS1", "C-RS1", "C-BS", "M-CS2")
LIGHTS = (("GREEN",), ("RED",), ("GREEN", "YELLOW"))


def _stream(seed: int, n: int, t0: float = 0.0):
    """Observations as three robots (and now and then the refbox) send them while
    they come and go: bursts of updates within a visit, silences between visits."""
    rnd = random.Random(seed)
    t = t0
    for _ in range(n):
        t += rnd.choice((0.2, 0.5, 1.0, 12.0))
        robot = REFBOX if rnd.random() < 0.02 else rnd.choice(("R1", "R2", "R3"))
        machine, prop = rnd.choice(MACHINES), rnd.choice(M.PROPERTIES)
        value = {M.ZONE: rnd.choice((3, 4, 17)), M.ORIENTATION: rnd.choice((0, 45, 90)),
                 M.LIGHT: rnd.choice(LIGHTS), M.TYPE: rnd.choice(("CS", "RS", "BS")),
                 M.POSE: (rnd.uniform(-5, 5), rnd.uniform(0, 8), rnd.uniform(-3, 3))}[prop]
        yield M.Observation(machine, prop, value, round(rnd.uniform(0.05, 1.0), 3), robot, t)


def _beliefs(kb: KnowledgeBase) -> dict:
    """Everything a decision reads of the fused observations, exactly."""
    out = {}
    for name, mb in kb.machines.items():
        for prop, belief in mb.props.items():
            out[name, prop] = (belief.estimate(), belief.distribution() if prop != M.POSE else None)
    return out


def test_observations_past_the_limit_are_folded_and_the_beliefs_stay_exactly_the_same(tmp_path):
    path = tmp_path / "ts.sqlite"
    kb = KnowledgeBase.load(P16, Store(path), observation_limit=200)
    whole = KnowledgeBase(P16)                                  # keeps every observation
    rows = []
    for obs in _stream(1, 3000):
        kb.add_observation(obs)
        whole.add_observation(obs)
        rows.append(kb.store.count_observations())
    assert kb.folds >= 2 and whole.store.count_observations() == 3000
    votes = sum(len(b.rows()) for mb in kb.machines.values() for b in mb.props.values())
    assert max(rows) <= max(200, 2 * votes) + 1                 # bounded by the limit or the votes
    assert kb.observation_count == whole.observation_count == 3000
    assert _beliefs(kb) == _beliefs(whole)

    # a restart reads the folded rows back: the same beliefs, the same count
    kb.store.close()
    again = KnowledgeBase.load(P16, Store(path), observation_limit=200)
    assert _beliefs(again) == _beliefs(whole) and again.observation_count == 3000
    # and the game goes on alike: updates within a visit merge as they would have
    for obs in _stream(2, 500, t0=max(o.time for o in _stream(1, 3000)) + 0.1):
        again.add_observation(obs)
        whole.add_observation(obs)
    assert _beliefs(again) == _beliefs(whole)


def test_a_fold_is_one_transaction_a_failure_leaves_the_old_rows(tmp_path):
    store = Store(tmp_path / "ts.sqlite")
    store.add_observation("C-BS", M.ZONE, 3, 0.8, "R1", 1.0)
    store.add_observation("C-BS", M.ZONE, 3, 0.9, "R2", 2.0)

    def rows():
        yield ("C-BS", M.ZONE, 3, 0.9, "R1", 2.0)
        raise RuntimeError("killed")
    with pytest.raises(RuntimeError):
        store.replace_observations(rows(), {"observations_folded": 1})
    assert [o[4] for o in store.observations()] == ["R1", "R2"] and store.get_meta("observations_folded") is None
    store.add_observation("C-BS", M.ZONE, 4, 0.5, "R3", 3.0)             # the store still works
    assert store.count_observations() == 3


def test_the_write_ahead_log_is_cut_back_once_a_reader_let_it_grow(tmp_path):
    import sqlite3
    store = Store(tmp_path / "ts.sqlite")
    wal = tmp_path / "ts.sqlite-wal"
    store.put("task", 0, {"i": 0})
    reader = sqlite3.connect(tmp_path / "ts.sqlite", isolation_level=None)   # a status reader, slow
    reader.execute("BEGIN")
    reader.execute("SELECT COUNT(*) FROM records").fetchone()
    blob = "x" * 4000
    for i in range(3000):                          # ~12 MB: no checkpoint can pass the reader
        store.put("task", i % 50, {"i": i, "pad": blob})
    assert wal.stat().st_size > 2 * WAL_LIMIT
    reader.execute("COMMIT")
    reader.close()
    for i in range(1200):                          # the next automatic checkpoints truncate it
        store.put("task", i % 50, {"i": i, "pad": blob})
    assert wal.stat().st_size <= WAL_LIMIT + (1 << 20)
    assert store.db.execute("SELECT COUNT(*) FROM records").fetchone()[0] == 50
