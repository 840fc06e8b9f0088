"""Fixtures for the rll_bt.comm tests."""
from __future__ import annotations

import types

import pytest

from tests.support.comm import TM, registry


@pytest.fixture(scope="session")
def tm():
    """The test message classes of :mod:`comm_testkit` plus ``tm.registry()``."""
    ns = types.SimpleNamespace(**vars(TM))
    ns.registry = registry
    return ns
