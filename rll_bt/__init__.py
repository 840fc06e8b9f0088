"""rll-bt: a RoboCup Logistics League fleet framework.

Kernel and mid-level: wire protocol (:mod:`rll_bt.comm`), message sets
(:mod:`rll_bt.msgs`), rules profiles (:mod:`rll_bt.rules`), clocks
(:mod:`rll_bt.clock`), the backend interface (:mod:`rll_bt.backend`), the
YAML behaviour-tree engine (:mod:`rll_bt.tree`), the robot agent
(:mod:`rll_bt.agent`) and the command line (:mod:`rll_bt.cli`).
"""

__version__ = "0.1.0"
