"""The ``rll-bt`` command line.

Commands come from the kernel itself and from the ``rll_bt.commands`` entry
points of the other packages, so ``rll_bt`` never imports them by name.  A
plug-in's ``register(cli)`` adds parsers through :meth:`Commands.group`.

Exit codes: 0 success, 1 the work failed, 2 bad usage or input,
3 a device or peer was unreachable, 130 interrupted.
"""
from __future__ import annotations

import argparse
import logging
import sys

from .. import __version__, plugins
from ..errors import UserError

EXIT_OK, EXIT_FAILURE, EXIT_USAGE, EXIT_UNAVAILABLE, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

#: kernel command modules, each with ``register(cli)``
_KERNEL_COMMANDS = ("rll_bt.cli.refbox", "rll_bt.cli.tree", "rll_bt.cli.treexml", "rll_bt.cli.agent")

GROUP_HELP = {
    "refbox": "talk to (or simulate) the referee box",
    "robotino": "Robotino base: emulator, probe and bring-up",
    "tree": "validate, show, list and run YAML behaviour trees",
    "vision": "signal-light and tag detection",
    "teamserver": "the team server",
    "sim": "simulated games and worlds",
}


class Commands:
    """Holds the top-level parser and hands out command groups."""

    def __init__(self) -> None:
        self.parser = argparse.ArgumentParser(
            prog="rll-bt",
            description="RoboCup Logistics League fleet framework: behaviour trees, "
                        "skills, simulation, team server and refbox tools.",
            epilog="exit codes: 0 ok, 1 failed, 2 bad usage or input, 3 unreachable, 130 interrupted")
        self.parser.add_argument("--version", action="version", version=f"rll-bt {__version__}")
        self.parser.add_argument("-v", "--verbose", action="count", default=0,
                                 help="more log output (repeat for debug)")
        self._top = self.parser.add_subparsers(dest="command", metavar="COMMAND")
        self._groups: dict[str, argparse._SubParsersAction] = {}
        self._group_parsers: dict[str, argparse.ArgumentParser] = {}

    def command(self, name: str, help: str, **kw) -> argparse.ArgumentParser:
        """A top-level command (``rll-bt NAME``)."""
        return self._top.add_parser(name, help=help, description=help, **kw)

    def group(self, name: str, help: str | None = None) -> argparse._SubParsersAction:
        """Subparsers of a command group (``rll-bt NAME SUB``), created once."""
        if name not in self._groups:
            text = help or GROUP_HELP.get(name, name)
            gp = self._top.add_parser(name, help=text, description=text)
            gp.set_defaults(func=lambda args, _gp=gp: _gp.print_help() or EXIT_USAGE)
            self._group_parsers[name] = gp
            self._groups[name] = gp.add_subparsers(dest=f"{name}_command", metavar="SUBCOMMAND")
        return self._groups[name]

    def group_parser(self, name: str) -> argparse.ArgumentParser:
        self.group(name)
        return self._group_parsers[name]


def build() -> Commands:
    import importlib
    cli = Commands()
    for modname in _KERNEL_COMMANDS:
        try:
            mod = importlib.import_module(modname)
        except ModuleNotFoundError as exc:
            if exc.name != modname:
                raise
            continue
        mod.register(cli)
    for _name, register in sorted(plugins.load_all("rll_bt.commands").items()):
        register(cli)
    return cli


def main(argv: list[str] | None = None) -> int:
    cli = build()
    args = cli.parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2),
                        format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "func", None):
        cli.parser.print_help()
        return EXIT_USAGE
    try:
        rc = args.func(args)
    except UserError as exc:
        print(f"rll-bt: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("rll-bt: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK
    return EXIT_OK if rc is None else int(rc)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
