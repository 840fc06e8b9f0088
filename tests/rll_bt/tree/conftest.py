"""Fixtures of the tree-engine tests: ``registry``, ``clock``, ``make`` and
``check`` (defined in :mod:`tests.support.trees`)."""
from tests.support.trees import check, clock, make, registry

__all__ = ["check", "clock", "make", "registry"]
