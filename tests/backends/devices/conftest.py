"""Shared helpers of the device tests."""
import os
import time

import pytest

#: factor on every wait (a loaded CI machine is slower; a wait ends as soon as its condition holds)
SLACK = float(os.environ.get("RLLBT_TEST_SLACK", "5"))


def _wait_for(predicate, timeout, period=0.01):
    end = time.monotonic() + timeout * SLACK
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period)
    return predicate()


@pytest.fixture
def wait_for():
    return _wait_for
