"""Helpers shared by the test packages (imported as ``tests.support.NAME``)."""
import os
from pathlib import Path

#: the repository's root folder
REPO = Path(__file__).resolve().parents[2]
#: the shipped behaviour trees
TREES = REPO / "trees"
#: what a test run keeps for people to look at (screenshots of the live page): outside pytest's
#: temporary folders, which keep only the last few runs; RLL_BT_TEST_OUTPUT moves it
OUTPUT = Path(os.environ.get("RLL_BT_TEST_OUTPUT") or REPO / "test-output")
