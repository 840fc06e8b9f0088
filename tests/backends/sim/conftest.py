import pytest

from backends.sim import FieldLayout, World


@pytest.fixture
def make_world():
    """World factory; every world made is closed after the test."""
    made = []

    def make(*args, **kw):
        w = World(*args, **kw)
        made.append(w)
        return w

    yield make
    for w in made:
        w.close()


@pytest.fixture
def world(make_world):
    return make_world("rcll2016", seed=3)


@pytest.fixture
def empty_world(make_world):
    """A 2016 field with walls but no stations."""
    return make_world("rcll2016", seed=3, layout=FieldLayout("rcll2016", {}, seed=3))
