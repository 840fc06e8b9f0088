"""Shared helpers of the robotino tests."""
import time

import pytest


def _wait_for(predicate, timeout, period=0.01):
    """Poll ``predicate`` until it is true or ``timeout`` seconds pass; its last value."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period)
    return predicate()


@pytest.fixture
def wait_for():
    return _wait_for
