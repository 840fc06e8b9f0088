"""SQLite persistence of the knowledge base (WAL mode, write-through).

Tables:
- ``observations``: every machine observation as received, append-only, in
  arrival order (fused beliefs are recomputed from them on load);
- ``records(kind, key, data)``: one JSON row per robot, order, station,
  workpiece, task, product, visited zone, sent report, ...;
- ``meta(key, value)``: JSON scalars (team colour, phase, counters).

Every change is committed at once, so a killed server loses nothing it had
acknowledged.  ``":memory:"`` keeps everything in RAM (tests, benchmarks).
Other processes (``rll-bt teamserver status``) may read the file while the
server writes: WAL lets readers and one writer work side by side.

Bounds: ``records`` and ``meta`` hold one row per thing the team knows (a
task, an order, a product...), rewritten in place, so they grow only with the
work done.  ``observations`` grows with every message of the robots: the
knowledge base folds it (:meth:`Store.replace_observations`, one transaction,
so a kill in between leaves the old rows or the new ones) into what its
beliefs hold once it passes a limit.  The write-ahead log is checkpointed by
SQLite every 1000 pages and cut back to ``WAL_LIMIT`` bytes after each
checkpoint (``journal_size_limit``).
"""
from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rll_bt.errors import UserError

SCHEMA_VERSION = 1
#: bytes the write-ahead log is cut back to after a checkpoint
WAL_LIMIT = 4 << 20

_SCHEMA = """
CREATE TABLE IF NOT EXISTS observations (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    machine TEXT NOT NULL, prop TEXT NOT NULL, value TEXT NOT NULL,
    confidence REAL NOT NULL, robot TEXT NOT NULL, time REAL NOT NULL);
CREATE TABLE IF NOT EXISTS records (
    kind TEXT NOT NULL, key TEXT NOT NULL, data TEXT NOT NULL,
    PRIMARY KEY (kind, key));
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
"""


class Store:
    """The database behind a :class:`~teamserver.knowledge.kb.KnowledgeBase`."""

    def __init__(self, path: str | Path = ":memory:", *, readonly: bool = False):
        self.path = str(path)
        try:
            if readonly:
                if not Path(self.path).exists():
                    raise UserError("no team server state database here", where=self.path,
                                    hint="pass --state FILE of a server that has run")
                uri = f"file:{Path(self.path).resolve()}?mode=ro"
                self.db = sqlite3.connect(uri, uri=True, isolation_level=None)
            else:
                if self.path != ":memory:":
                    Path(self.path).parent.mkdir(parents=True, exist_ok=True)
                self.db = sqlite3.connect(self.path, isolation_level=None)
                self.db.execute("PRAGMA journal_mode=WAL")
                self.db.execute("PRAGMA synchronous=NORMAL")
                self.db.execute(f"PRAGMA journal_size_limit={WAL_LIMIT}")
                self.db.executescript(_SCHEMA)
                if self.get_meta("schema") is None:
                    self.set_meta("schema", SCHEMA_VERSION)
            schema = self.get_meta("schema")
        except sqlite3.DatabaseError as exc:
            raise UserError(f"not a team server state database ({exc})", where=self.path) from None
        if schema is not None and schema != SCHEMA_VERSION:
            raise UserError(f"state database schema {schema}, this server writes "
                            f"{SCHEMA_VERSION}", where=self.path,
                            hint="start with a fresh --state file")

    @property
    def journal_mode(self) -> str:
        return self.db.execute("PRAGMA journal_mode").fetchone()[0]

    # -- observations ------------------------------------------------------
    def add_observation(self, machine: str, prop: str, value: Any, confidence: float,
                        robot: str, time: float) -> None:
        self.db.execute("INSERT INTO observations (machine, prop, value, confidence, robot, time)"
                        " VALUES (?, ?, ?, ?, ?, ?)",
                        (machine, prop, json.dumps(value), confidence, robot, time))

    def observations(self) -> Iterator[tuple[str, str, Any, float, str, float]]:
        for m, p, v, c, r, t in self.db.execute(
                "SELECT machine, prop, value, confidence, robot, time FROM observations "
                "ORDER BY seq"):
            yield m, p, json.loads(v), c, r, t

    def count_observations(self) -> int:
        return self.db.execute("SELECT COUNT(*) FROM observations").fetchone()[0]

    def replace_observations(self, rows, meta: dict[str, Any] | None = None) -> None:
        """All observations replaced by ``rows`` ((machine, prop, value, confidence,
        robot, time), in this order) and ``meta`` set, in one transaction."""
        db = self.db
        db.execute("BEGIN IMMEDIATE")
        try:
            db.execute("DELETE FROM observations")
            db.executemany("INSERT INTO observations (machine, prop, value, confidence, robot, time)"
                           " VALUES (?, ?, ?, ?, ?, ?)",
                           ((m, p, json.dumps(v), c, r, t) for m, p, v, c, r, t in rows))
            for key, value in (meta or {}).items():
                self.set_meta(key, value)
        except BaseException:
            db.execute("ROLLBACK")
            raise
        db.execute("COMMIT")

    # -- records -------------------------------------------------------------
    def put(self, kind: str, key: Any, data: Any) -> None:
        self.db.execute("INSERT OR REPLACE INTO records (kind, key, data) VALUES (?, ?, ?)",
                        (kind, str(key), json.dumps(data, sort_keys=True)))

    def delete(self, kind: str, key: Any) -> None:
        self.db.execute("DELETE FROM records WHERE kind = ? AND key = ?", (kind, str(key)))

    def all(self, kind: str) -> Iterator[tuple[str, Any]]:
        for key, data in self.db.execute("SELECT key, data FROM records WHERE kind = ? "
                                         "ORDER BY rowid", (kind,)):
            yield key, json.loads(data)

    # -- meta ------------------------------------------------------------------
    def set_meta(self, key: str, value: Any) -> None:
        self.db.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                        (key, json.dumps(value)))

    def get_meta(self, key: str, default: Any = None) -> Any:
        row = self.db.execute("SELECT value FROM meta WHERE key = ?", (key,)).fetchone()
        return default if row is None else json.loads(row[0])

    def close(self) -> None:
        self.db.close()
