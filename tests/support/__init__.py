"""Helpers shared by the test packages (imported as ``tests.support.NAME``)."""
from pathlib import Path

#: the repository's root folder
REPO = Path(__file__).resolve().parents[2]
#: the shipped behaviour trees
TREES = REPO / "trees"
