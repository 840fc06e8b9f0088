"""Shared helpers of the robotino tests."""
import os
import time

import pytest

#: factor on every wait: the limits are what an idle machine needs; a loaded
#: CI machine (pytest -n 2 on 2 cores) can be several times slower, and a wait
#: returns as soon as its condition holds, so slack costs nothing when it passes
SLACK = float(os.environ.get("RLLBT_TEST_SLACK", "5"))
#: the shortest wait: it only guards against a hang (a wait returns as soon as its condition
#: holds, so a long one costs nothing when the test passes); no test asserts on how fast
#: something happened: that is the benchmarks' business
LIVENESS = 120.0


def _wait_for(predicate, timeout, period=0.01):
    """Poll ``predicate`` until it is true or ``timeout`` x SLACK seconds pass; its last value."""
    end = time.monotonic() + max(timeout * SLACK, LIVENESS)
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(period)
    return predicate()


@pytest.fixture
def wait_for():
    return _wait_for
