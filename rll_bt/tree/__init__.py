"""The YAML behaviour-tree engine.

Load and run a tree::

    from rll_bt.tree import load_tree, RunContext
    tree = load_tree("trees/explore_zone.yaml", task={"zone": "C_Z12"},
                     ctx=RunContext(backend=robot, clock=clock))
    status = tree.run(hz=10)

Write a node type::

    from rll_bt.tree import Node, Input, Output, Status, node_type

    @node_type("grab")
    class Grab(Node):
        \"\"\"Grab a workpiece from the station side in front of the robot.\"\"\"
        side = Input(str, "station side", choices=("input", "output"))
        holding = Output(bool, "whether the gripper holds a workpiece afterwards")

        def initialise(self): ...      # start (never block)
        def update(self): ...          # poll: RUNNING / SUCCESS / FAILURE
        def terminate(self, new_status): ...   # INVALID: cancel and stop

The YAML format is described in ``docs/trees.md``.
"""
from py_trees.common import Status

from .blackboard import ERROR_CODE_KEY, ERROR_MESSAGE_KEY, ERROR_NODE_KEY, Blackboard, clear_error, write_error
from .build import build_tree, load_tree
from .context import RunContext, register_service
from .errors import Diagnostic, Loc, TreeLoadError, TreeRuntimeError
from .expr import Expr, ExprError, parse_expr
from .loader import CliText, parse_tree
from .node import Node
from .ports import BB, BoundPorts, Const, Input, Key, Output, Port
from .porttypes import PortType, PortTypeError, port_type, register_type
from .registry import NodeRegistry, NodeType, Slot, default_registry, node_type, register, structural
from .runtime import LoadedTree, NodeInfo, TreeFailure
from .spec import NodeSpec, TreeSpec

__all__ = [
    "Status", "Blackboard", "ERROR_CODE_KEY", "ERROR_MESSAGE_KEY", "ERROR_NODE_KEY", "write_error", "clear_error",
    "build_tree", "load_tree", "parse_tree", "CliText", "RunContext", "register_service", "Diagnostic", "Loc",
    "TreeLoadError", "TreeRuntimeError", "Expr", "ExprError", "parse_expr", "Node", "BB", "BoundPorts", "Const",
    "Input", "Key", "Output", "Port", "PortType", "PortTypeError", "port_type", "register_type", "NodeRegistry",
    "NodeType", "Slot", "default_registry", "node_type", "register", "structural", "LoadedTree", "NodeInfo",
    "TreeFailure", "NodeSpec", "TreeSpec",
]
