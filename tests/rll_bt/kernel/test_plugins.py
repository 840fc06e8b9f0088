"""Entry-point discovery for the plug-in groups."""
import sys
import types
from importlib.metadata import EntryPoint

import pytest

from rll_bt import backend, plugins
from rll_bt.backend import Backend, BackendUnavailable, Capability, Odometry, Pose2D


class _FakeBackend(Backend):
    name = "fake"

    def __init__(self, speed=1.0):
        self.speed = speed
        self.cmd = None
        self.closed = False

    @property
    def capabilities(self):
        return Capability.DRIVE | Capability.ODOMETRY

    def drive(self, vx, vy, omega):
        self.cmd = (vx, vy, omega)

    def odometry(self):
        return Odometry(0.0, Pose2D())

    def close(self):
        self.closed = True


@pytest.fixture
def fake_group(monkeypatch):
    mod = types.ModuleType("rll_bt_test_fake_plugin")
    mod.FakeBackend = _FakeBackend
    mod.not_a_backend = lambda **kw: object()
    monkeypatch.setitem(sys.modules, mod.__name__, mod)
    eps = {
        "fake": EntryPoint("fake", f"{mod.__name__}:FakeBackend", backend.ENTRY_POINT_GROUP),
        "bogus": EntryPoint("bogus", f"{mod.__name__}:not_a_backend", backend.ENTRY_POINT_GROUP),
        "broken": EntryPoint("broken", "no_such_module_xyz:thing", backend.ENTRY_POINT_GROUP),
    }
    real = plugins.discover
    monkeypatch.setattr(plugins, "discover",
                        lambda group: eps if group == backend.ENTRY_POINT_GROUP else real(group))
    return eps


def test_open_backend_by_entry_point(fake_group):
    assert "fake" in backend.available_backends()
    with backend.open_backend("fake", speed=2.0) as robot:
        assert robot.speed == 2.0
        robot.drive(0.1, 0.2, 0.3)
        assert robot.cmd == (0.1, 0.2, 0.3)
    assert robot.closed and robot.cmd == (0.0, 0.0, 0.0)   # __exit__ stops, then closes


def test_unknown_backend_names_the_known_ones(fake_group):
    with pytest.raises(BackendUnavailable, match="fake"):
        backend.open_backend("nope")


def test_factory_must_return_a_backend(fake_group):
    with pytest.raises(backend.BackendError, match="not a Backend"):
        backend.open_backend("bogus")


def test_broken_plugin_is_logged_not_fatal(fake_group, caplog):
    loaded = plugins.load_all(backend.ENTRY_POINT_GROUP)
    assert "fake" in loaded and "broken" not in loaded
    assert "broken" in caplog.text


def test_missing_capability_raises():
    b = _FakeBackend()
    with pytest.raises(backend.CapabilityError):
        b.laser_scan()
    with pytest.raises(backend.CapabilityError):
        b.gripper_close()


def test_installed_groups_resolve():
    """Every entry point the installed distribution declares actually loads."""
    for group in plugins.GROUPS:
        for name, ep in plugins.discover(group).items():
            assert ep.load() is not None, (group, name)


# -- option choices published by plug-ins ---------------------------------------------------
@pytest.fixture
def choice_group(monkeypatch):
    mod = types.ModuleType("rll_bt_test_choices_plugin")

    @plugins.offers(mode=("fast", "exact"))
    def first(**kw):
        return kw

    @plugins.offers(mode=("exact", "rendered"), speed=("1", "2"))
    def second(**kw):
        return kw
    mod.first, mod.second = first, second
    mod.silent = lambda **kw: kw
    monkeypatch.setitem(sys.modules, mod.__name__, mod)
    group = "rll_bt.test_choices"
    eps = {n: EntryPoint(n, f"{mod.__name__}:{n}", group) for n in ("first", "second", "silent")}
    real = plugins.discover
    monkeypatch.setattr(plugins, "discover", lambda g: eps if g == group else real(g))
    return group


def test_choices_are_what_the_entry_points_publish(choice_group):
    assert plugins.choices(choice_group, "mode", "first") == ("fast", "exact")
    assert plugins.choices(choice_group, "mode") == ("fast", "exact", "rendered")   # each once, in order
    assert plugins.choices(choice_group, "speed") == ("1", "2")
    assert plugins.choices(choice_group, "mode", "silent") == ()
    with pytest.raises(KeyError, match="first"):
        plugins.choices(choice_group, "mode", "nope")


def test_lazy_choices_load_on_first_use(choice_group, monkeypatch):
    loads = []
    real = plugins.choices
    monkeypatch.setattr(plugins, "choices", lambda *a: loads.append(a) or real(*a))
    c = plugins.Choices(choice_group, "mode")
    assert loads == []
    assert "rendered" in c and "slow" not in c and list(c) == ["fast", "exact", "rendered"]
    assert len(loads) == 1


def test_the_shipped_plugins_publish_their_choices():
    """What rll-bt sim and rll-bt agent offer comes from the plug-ins themselves."""
    from skills.localisation.config import AmclConfig
    from teamserver.exploration.strategies import STRATEGIES
    assert plugins.choices("rll_bt.teamservers", "strategy", "htn") == tuple(STRATEGIES)
    assert plugins.choices("rll_bt.simulators", "perception", "pybullet") == ("oracle", "rendered")
    presets = plugins.choices("rll_bt.nodes", "localisation")
    assert presets == ("cheap", "standard")
    for name in presets:
        AmclConfig.preset(name)
