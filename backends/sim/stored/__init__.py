"""Stored games: the field and orders of a game, saved and loaded, and read
from the refbox's own game reports (:mod:`.game`, :mod:`.archive`)."""
from .archive import ArchiveError, game_reports, read_archive
from .game import StoredGame, StoredGameError, StoredOrder, load_game, read_refbox_games

__all__ = ["ArchiveError", "StoredGame", "StoredGameError", "StoredOrder", "game_reports", "load_game",
           "read_archive", "read_refbox_games"]
