"""The results of a tournament on disk, so a killed tournament resumes.

One SQLite file (``tournament.sqlite`` in the tournament's folder): the
shared game settings it was started with, and one row per game played,
written in its own transaction as the game's result arrives (a tournament
killed at any moment keeps every game that had finished).  A store started
with other settings refuses to mix them in: the table would compare games
of different lengths or rules.  More seeds (``--seeds`` raised) or more
configurations later only add games.
"""
from __future__ import annotations

import json
import sqlite3
from pathlib import Path

FILE = "tournament.sqlite"


class StoreError(ValueError):
    """The store cannot be used for this tournament (other settings, not a store)."""


class Store:
    def __init__(self, folder: str | Path, shared: dict):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path = self.folder / FILE
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0)
            self.db.execute("CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT NOT NULL)")
            self.db.execute("CREATE TABLE IF NOT EXISTS games (key TEXT PRIMARY KEY, played INTEGER NOT NULL, "
                            "row TEXT NOT NULL)")
            self.db.commit()
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{self.path} is not a tournament store ({exc})") from None
        got = self.db.execute("SELECT value FROM meta WHERE name = 'settings'").fetchone()
        wanted = json.dumps(shared, sort_keys=True)
        if got is None:
            with self.db:
                self.db.execute("INSERT INTO meta VALUES ('settings', ?)", (wanted,))
        elif got[0] != wanted:
            raise StoreError(f"{self.path} holds a tournament played with other settings "
                             f"({_diff(json.loads(got[0]), shared)}): resume it with those, or give another --out")

    def rows(self) -> dict[str, dict]:
        """key -> row of every game played, in the order they were stored."""
        return {k: json.loads(r) for k, r in self.db.execute("SELECT key, row FROM games ORDER BY played, key")}

    def add(self, row: dict) -> None:
        """Keep the row of a played game (a game played again replaces its row)."""
        n = self.db.execute("SELECT COUNT(*) FROM games").fetchone()[0]
        with self.db:
            self.db.execute("INSERT OR REPLACE INTO games VALUES (?, ?, ?)",
                            (row["key"], n, json.dumps(row, sort_keys=True)))

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _diff(old: dict, new: dict) -> str:
    return ", ".join(f"{k} {old.get(k)!r} there, {new.get(k)!r} now" for k in sorted(set(old) | set(new))
                     if old.get(k) != new.get(k))
