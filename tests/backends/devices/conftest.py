"""Shared helpers of the device tests."""
import os
import time

import pytest

#: factor on every wait (a loaded CI machine is slower; a wait ends as soon as its condition holds)
SLACK = float(os.environ.get("RLLBT_TEST_SLACK", "5"))
#: the shortest wait: it only guards against a hang (a wait returns as soon as its condition
#: holds, so a long one costs nothing when the test passes); no test asserts on how fast
#: something happened: that is the benchmarks' business
LIVENESS = 120.0


def _wait_for(predicate, timeout, period=0.01):
    end = time.monotonic() + max(timeout * SLACK, LIVENESS)
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period)
    return predicate()


@pytest.fixture
def wait_for():
    return _wait_for

