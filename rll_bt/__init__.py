"""rll-bt: a RoboCup Logistics League fleet framework.

The kernel and the mid-level: wire protocol and transports
(:mod:`rll_bt.comm`), message sets (:mod:`rll_bt.msgs`), rules profiles
(:mod:`rll_bt.rules`), clocks (:mod:`rll_bt.clock`), the backend interface
and its check (:mod:`rll_bt.backend`), the YAML behaviour-tree engine
(:mod:`rll_bt.tree`), the robot agent (:mod:`rll_bt.agent`), the plug-in
contracts of a game (:mod:`rll_bt.contracts`), plug-in discovery
(:mod:`rll_bt.plugins`) and the command-line frame (:mod:`rll_bt.cli`).
Whole games are an application above it (the ``games`` package); see
``docs/architecture.md``.
"""

from . import blas as _blas

_blas.pin_kernel()  # before numpy loads: the same game for a seed on every machine

__version__ = "0.1.0"
