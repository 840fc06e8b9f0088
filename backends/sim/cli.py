"""``rll-bt sim world``: generate a field and show it.

    rll-bt sim world --profile rcll2016 --seed 7 --png field.png
    rll-bt sim world --seed 7 --gui          # PyBullet's own window

Without ``--png`` or ``--gui`` the placement is printed as a table (or as
JSON with ``--json``).  Imports of PyBullet and matplotlib happen only when a
command runs.
"""
from __future__ import annotations

import json
import os
import sys

from rll_bt.errors import Unavailable, UserError


def register(cli) -> None:
    sub = cli.group("sim")
    p = sub.add_parser("world", help="generate a field layout; draw it (--png) or open it (--gui)",
                       description="Generate the seeded field layout of a rules profile, print its "
                                   "placement, draw a top view to PNG and/or open it in PyBullet's window.")
    p.add_argument("--profile", default="rcll2016", help="rules profile (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="layout seed (default: %(default)s)")
    p.add_argument("--png", metavar="FILE", help="write a top view of the field to FILE")
    p.add_argument("--gui", action="store_true",
                   help="open the world in PyBullet's window (needs a display); close it to exit")
    p.add_argument("--json", action="store_true", help="print the layout as JSON")
    p.set_defaults(func=run_world)


def _profile(name: str):
    from rll_bt import rules
    try:
        return rules.profile(name)
    except ValueError as exc:
        raise UserError(str(exc), where="--profile") from None


def run_world(args) -> int:
    from .layout import LayoutError, generate_layout
    prof = _profile(args.profile)
    if args.gui:
        from .bullet import display_available
        if not display_available():
            raise Unavailable("cannot open the PyBullet window: no display (DISPLAY/WAYLAND_DISPLAY unset)",
                              hint="use --png for a picture without a display")
    if args.png:
        folder = os.path.dirname(os.path.abspath(args.png))
        if not os.path.isdir(folder):
            raise UserError(f"directory {folder} does not exist", where="--png")
    try:
        layout = generate_layout(prof, args.seed)
    except LayoutError as exc:
        print(f"rll-bt: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(layout.to_dict(), indent=2))
    else:
        _print_table(prof, layout)
    if args.png:
        from .topview import draw_layout
        try:
            draw_layout(prof, layout, args.png)
        except OSError as exc:
            raise UserError(f"cannot write the PNG: {exc}", where=args.png) from None
        print(f"wrote {args.png}", file=sys.stderr)
    if args.gui:
        return _gui(prof, layout)
    return 0


def _print_table(prof, layout) -> None:
    print(f"{prof.name} seed {layout.seed}, swapped: {', '.join(layout.swapped) or 'none'}")
    print(f"{'machine':8} {'zone':>6} {'rot':>4} {'x':>7} {'y':>7}  tags (in/out)")
    for m in layout:
        pl = layout[m]
        tin, tout = prof.tag_ids(m)
        print(f"{m:8} {prof.zone_name(pl.zone):>6} {pl.rotation_deg:>4} {pl.pose.x:7.3f} {pl.pose.y:7.3f}"
              f"  {tin}/{tout}")


def _gui(prof, layout) -> int:
    from rll_bt.backend import BackendUnavailable
    from rll_bt.clock import WallClock

    from .world import World
    try:
        world = World(prof, layout.seed or 0, layout=layout, gui=True)
    except BackendUnavailable as exc:
        raise Unavailable(str(exc)) from None
    wall = WallClock()
    print("PyBullet window open; close it (or press Ctrl-C) to exit", file=sys.stderr)
    with world:
        for team in ("CYAN", "MAGENTA"):
            for n in (1, 2, 3):
                world.add_robot(team, n)
        while world.connected:
            world.step(1.0 / 30.0)
            wall.sleep(1.0 / 30.0)
    return 0
