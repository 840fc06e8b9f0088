"""Test-session set-up shared by every test."""
from importlib.metadata import version

import pytest

import rll_bt  # noqa: F401  (before any test module: pins OpenBLAS's kernel before numpy loads)


def pytest_configure(config):
    """Under ``--dist loadgroup`` the tests of an ``xdist_group`` go to one
    worker (a module's costly fixture is built once, wall-clock games do not
    run side by side).  pytest-xdist 3.8 marks a grouped test by renaming its
    node id, which pytest 9 no longer takes: the groups would be spread over
    the workers silently, so that pair stops the run with the one fix."""
    if getattr(config.option, "dist", "no") != "loadgroup" or pytest.version_tuple[0] < 9:
        return
    if tuple(int(p) for p in version("pytest-xdist").split(".")[:2]) <= (3, 8):
        raise pytest.UsageError(f"pytest {pytest.__version__} with pytest-xdist {version('pytest-xdist')} "
                                "ignores xdist_group: pip install 'pytest<9' (pyproject.toml's test extra)")
