"""The node-type API that skill authors use."""
import pytest

from rll_bt.backend import Capability
from rll_bt.clock import SimClock
from rll_bt.tree import (
    BB,
    Input,
    Node,
    NodeRegistry,
    Output,
    RunContext,
    Status,
    TreeLoadError,
    default_registry,
    load_tree,
    node_type,
    register_service,
)


def test_declared_ports_read_and_write_the_blackboard(tmp_path):
    reg = default_registry().child()

    @node_type("double", registry=reg)
    class Double(Node):
        """Write twice the input to the output."""
        kind = "action"
        x = Input(float, "a number", default=1.5)
        out = Output(float, "twice x")

        def update(self):
            self.out = 2 * self.x
            return Status.SUCCESS

    assert set(Double.ports) == {"x", "out"} and Double.node_type == "double"
    desc = reg.get("double").describe()
    assert desc["ports"][0] == {"name": "x", "direction": "in", "type": "float", "doc": "a number",
                                "required": False, "constant": False, "default": 1.5}
    (tmp_path / "t.yaml").write_text("root:\n  reactive_sequence:\n    - double: {out: $bb.a}\n"
                                     "    - double: {x: $bb.a, out: $bb.b}\n")
    tree = load_tree(tmp_path / "t.yaml", registry=reg)
    assert tree.tick() is Status.SUCCESS
    assert tree.blackboard.snapshot() == {"/a": 3.0, "/b": 6.0}
    # from Python
    ctx = RunContext()
    n = Double.make(ctx, x=BB("a"), out=BB("b"))
    ctx.blackboard.set("/a", 4.0)
    n.tick_once()
    assert ctx.blackboard.get("/b") == 8.0
    with pytest.raises(AttributeError):
        n.x = 3


def test_reserved_port_names_and_docstrings_are_enforced():
    with pytest.raises(TypeError, match="reserved"):
        class Bad(Node):
            """x"""
            status = Input(str)
    reg = NodeRegistry()

    class NoDoc(Node):
        pass
    with pytest.raises(TypeError, match="needs a docstring"):
        reg.register(NoDoc, "no_doc")
    with pytest.raises(ValueError, match="lower_snake_case"):
        reg.register(type("Camel", (Node,), {"__doc__": "d"}), "Camel")


def test_duplicate_registration_is_refused():
    reg = default_registry().child()

    class A(Node):
        """a"""
    reg.register(A, "wait")   # a child registry may shadow a builtin
    with pytest.raises(ValueError, match="already registered"):
        reg.register(type("B", (Node,), {"__doc__": "b"}), "wait")


def test_services_and_capabilities_are_checked_at_build(tmp_path):
    reg = default_registry().child()

    @node_type("use_map", registry=reg)
    class UseMap(Node):
        """Needs the world map."""
        requires_services = ("world_map",)
        requires_capabilities = Capability.GRIPPER

        def initialise(self):
            self.map = self.ctx.service("world_map")

        def update(self):
            return Status.SUCCESS if self.map == "MAP" else Status.FAILURE

    p = tmp_path / "t.yaml"
    p.write_text("root: use_map\n")
    with pytest.raises(TreeLoadError, match="t.yaml:1:7: 'use_map' needs service"):
        load_tree(p, registry=reg)
    tree = load_tree(p, registry=reg, ctx=RunContext(services={"world_map": "MAP"}))
    assert tree.tick() is Status.SUCCESS

    class NoGripper:
        capabilities = Capability.DRIVE

        def stop(self):
            pass
    with pytest.raises(TreeLoadError, match="needs backend capabilities"):
        load_tree(p, registry=reg, ctx=RunContext(backend=NoGripper(), services={"world_map": "MAP"}))
    register_service("world_map", lambda ctx: "MAP", replace=True)
    assert load_tree(p, registry=reg).tick() is Status.SUCCESS


def test_plugin_function_registration(monkeypatch):
    from rll_bt import plugins
    from rll_bt.tree import registry as regmod

    class Hello(Node):
        """Say hello."""

    def register_nodes(reg):
        reg.register(Hello, "hello_plugin")

    monkeypatch.setattr(regmod, "_loaded", False)
    monkeypatch.setattr(regmod, "DEFAULT", NodeRegistry())
    monkeypatch.setattr(plugins, "load_all", lambda group: {"demo": register_nodes} if group == "rll_bt.nodes" else {})
    reg = regmod.default_registry()
    assert "hello_plugin" in reg
    monkeypatch.setattr(regmod, "_loaded", False)


def test_wait_uses_the_context_clock(tmp_path):
    clock = SimClock()
    p = tmp_path / "t.yaml"
    p.write_text("root:\n  wait: {seconds: 2.5}\n")
    tree = load_tree(p, ctx=RunContext(clock=clock))
    assert tree.run(hz=2) is Status.SUCCESS and clock.now() == 2.5
