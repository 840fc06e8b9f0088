"""``rll-bt tree``: validate, show, list node types, run, replay and schema.

Exit codes: 0 ok (tree valid, run ended in SUCCESS), 1 the run ended in
FAILURE or was stopped, 2 invalid tree or bad arguments, 3 the backend
could not be reached.
"""
from __future__ import annotations

import argparse
import inspect
import json
import sys
from pathlib import Path

from ..errors import Unavailable, UserError

EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2


def _pose(text: str):
    from ..backend import Pose2D
    try:
        x, y, theta = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,THETA (m, m, rad), got {text!r}") from None
    return Pose2D(x, y, theta)


def _kv(text: str) -> tuple[str, str]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    k, v = text.split("=", 1)
    if not k:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    return k, v


def _values(pairs) -> dict:
    from ..tree import CliText
    return {k: CliText(v) for k, v in (pairs or [])}


def register(cli) -> None:
    g = cli.group("tree")

    p = g.add_parser("validate", help="check tree files; print file:line:col errors",
                     description="Check tree files without running them.  Prints every problem as "
                                 "file:line:column with a hint.  Exit 0 when all are valid, 2 otherwise.")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.add_argument("--task", action="append", type=_kv, metavar="NAME=VALUE",
                   help="check with these task fields (default: check without a task)")
    p.add_argument("--param", action="append", type=_kv, metavar="NAME=VALUE", help="root parameters")
    p.add_argument("-I", "--search-path", action="append", default=[], metavar="DIR",
                   help="also look for subtree files here")
    p.add_argument("-q", "--quiet", action="store_true", help="print only errors")
    p.set_defaults(func=_validate)

    p = g.add_parser("show", help="draw a tree as text, DOT or PNG",
                     description="Draw a tree: indented text (default), Graphviz DOT text, or a PNG drawn "
                                 "with matplotlib.")
    p.add_argument("file", metavar="FILE")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--ascii", action="store_true", help="indented text (default)")
    fmt.add_argument("--dot", action="store_true", help="Graphviz DOT text on stdout")
    fmt.add_argument("--png", metavar="OUT", help="write a PNG picture to OUT")
    p.add_argument("--locations", action="store_true", help="show file:line:col of every node (text)")
    p.add_argument("-I", "--search-path", action="append", default=[], metavar="DIR")
    p.set_defaults(func=_show)

    p = g.add_parser("nodes", help="list node types with their ports and documentation",
                     description="List every registered node type (built-in and from rll_bt.nodes plug-ins) "
                                 "with its ports and documentation.")
    p.add_argument("types", nargs="*", metavar="TYPE", help="show only these types, in full")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--btcpp", action="store_true",
                   help="as a BehaviorTree.CPP 4 <TreeNodesModel> (load it into Groot2)")
    p.set_defaults(func=_nodes)

    p = g.add_parser("run", help="run a tree on a backend until it succeeds or fails",
                     description="Open a backend, load the tree for the given task and tick it until the root "
                                 "succeeds (exit 0) or fails (exit 1).  Ctrl-C halts the tree, stopping the robot.")
    p.add_argument("file", metavar="FILE")
    p.add_argument("--backend", required=True, metavar="NAME", help="backend name (rll_bt.backends entry point)")
    p.add_argument("--backend-opt", action="append", type=_kv, default=[], metavar="K=V",
                   help="backend option (value read as YAML: numbers, true/false, text)")
    p.add_argument("--task", action="append", type=_kv, metavar="NAME=VALUE", help="task field ($task.NAME)")
    p.add_argument("--param", action="append", type=_kv, metavar="NAME=VALUE", help="root parameter ($param.NAME)")
    p.add_argument("--hz", type=float, default=10.0, help="tick rate in Hz (default 10)")
    p.add_argument("--log", metavar="FILE", help="write a JSON-lines tick log")
    p.add_argument("--max-ticks", type=int, metavar="N", help="stop after N ticks (exit 1)")
    p.add_argument("--timeout", type=float, metavar="S", help="stop after S seconds of clock time (exit 1)")
    p.add_argument("--clock", choices=("wall", "sim"), default="wall",
                   help="wall: real time; sim: a simulated clock that jumps to the next tick (as fast as possible)")
    p.add_argument("--profile", choices=("rcll2016", "rcll2025"), default="rcll2016",
                   help="rules profile of the skills' map (and of a simulated world; default rcll2016)")
    p.add_argument("--start-pose", type=_pose, metavar="X,Y,THETA",
                   help="the robot's field pose at start (default: the skills localise globally)")
    p.add_argument("-I", "--search-path", action="append", default=[], metavar="DIR")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_run)

    p = g.add_parser("replay", help="print a JSON-lines tick log",
                     description="Print a tick log written by `rll-bt tree run --log`: per tick the visited "
                                 "nodes with their status, halted nodes and blackboard changes.")
    p.add_argument("log", metavar="LOG")
    p.add_argument("--from", dest="first", type=int, default=1, metavar="N", help="first tick to print")
    p.add_argument("--to", dest="last", type=int, metavar="N", help="last tick to print")
    p.add_argument("--state", action="store_true", help="also print every node's status and the whole "
                                                        "blackboard after the last printed tick")
    p.set_defaults(func=_replay)

    p = g.add_parser("schema", help="write the JSON Schema of tree files (with plug-in node types)",
                     description="Write the JSON Schema of tree files, covering every installed node type, "
                                 "for editor completion.")
    p.add_argument("-o", "--output", metavar="FILE", help="write here instead of stdout")
    p.add_argument("--builtin", action="store_true",
                   help="only the engine's own node types (the shipped rll_bt/tree/schema/tree.schema.json)")
    p.set_defaults(func=_schema)


def _parse(path: str, args, task=None, strict=False):
    from ..tree import parse_tree
    if not Path(path).exists():
        raise UserError("file not found", where=path, hint="check the path")
    return parse_tree(path, task=task, params=_values(getattr(args, "param", None)),
                      search_path=args.search_path, strict=strict)


def _validate(args) -> int:
    from ..tree import TreeLoadError
    bad = 0
    task = _values(args.task) if args.task else None
    for f in args.files:
        try:
            spec = _parse(f, args, task=task, strict=task is not None)
        except TreeLoadError as exc:
            bad += 1
            print(str(exc), file=sys.stderr)
            continue
        except UserError as exc:
            bad += 1
            print(str(exc), file=sys.stderr)
            continue
        if not args.quiet:
            extra = f", {len(spec.files) - 1} subtree file(s)" if len(spec.files) > 1 else ""
            if spec.outputs:
                extra += ", outputs: " + ", ".join(spec.outputs)
            print(f"{f}: ok ({spec.count()} nodes{extra})")
    if bad:
        print(f"{bad} of {len(args.files)} file(s) invalid", file=sys.stderr)
        return EXIT_USAGE
    return EXIT_OK


def _show(args) -> int:
    from ..tree.render import ascii_tree, dot_tree, png_tree
    spec = _parse(args.file, args)
    if args.dot:
        print(dot_tree(spec))
    elif args.png:
        out = png_tree(spec, args.png)
        print(f"wrote {out}")
    else:
        print(ascii_tree(spec, locations=args.locations))
    return EXIT_OK


def _nodes(args) -> int:
    from ..tree import default_registry
    reg = default_registry()
    types = reg.types()
    if args.types:
        missing = [t for t in args.types if t not in types]
        if missing:
            from ..tree.errors import did_you_mean
            raise UserError(f"unknown node type {missing[0]!r}", hint=did_you_mean(missing[0], types, "node types"))
        types = {t: types[t] for t in args.types}
    if args.btcpp:
        from ..tree.btcpp import nodes_model
        from ..tree.registry import NodeRegistry
        sub = NodeRegistry()
        for nt in types.values():
            sub.register(nt)
        sys.stdout.write(nodes_model(sub))
        return EXIT_OK
    if args.json:
        print(json.dumps([nt.describe() for nt in types.values()], indent=1, default=repr))
        return EXIT_OK
    full = bool(args.types)
    for name, nt in types.items():
        print(f"{name}  [{nt.kind}]  {nt.summary}")
        if full and nt.doc:
            for line in inspect.cleandoc(nt.doc).splitlines():
                print(f"  | {line}")
        for p in nt.ports.values():
            notes = ["required" if p.required else f"default {json.dumps(p.default, default=repr)}"]
            if p.direction == "out":
                notes = ["output: $bb.KEY"] + (["required"] if p.required else [])
            if p.choices:
                notes.append(f"one of {', '.join(map(str, p.choices))}")
            if p.constant and p.direction == "in":
                notes.append("fixed at load")
            print(f"    {p.name}: {p.ptype.name} ({'; '.join(notes)})  {p.doc}")
        for s in nt.slots:
            if nt.kind == "subtree":
                continue
            what = "list of nodes" if s.many else ("node or condition expression" if s.expr else "node")
            print(f"    {s.name}: {what}{'' if s.required else ' (optional)'} {s.doc}")
    return EXIT_OK


def _backend(args, clock):
    import yaml

    from .. import plugins
    from ..backend import BackendError, BackendUnavailable, open_backend
    opts = {}
    for k, v in args.backend_opt:
        try:
            opts[k] = yaml.safe_load(v)
        except yaml.YAMLError:
            opts[k] = v
    try:
        factory = plugins.load("rll_bt.backends", args.backend)
    except KeyError as exc:
        raise UserError(str(exc.args[0]), hint="`--backend` names an installed backend") from None
    robot_config = getattr(args, "robot_config", None)
    try:
        params = inspect.signature(factory).parameters
        if robot_config is not None:
            if "robot_config" not in params:
                raise UserError(f"backend {args.backend!r} takes no robot configuration",
                                where=f"--robot-config {robot_config}", hint="use --backend robotino")
            opts["robot_config"] = str(robot_config)
        if "clock" in params and "clock" not in opts:
            opts["clock"] = clock
        # a backend that builds its own world plays the run's rules profile
        if "profile" in params and "profile" not in opts and getattr(args, "profile", None):
            opts["profile"] = args.profile
    except (TypeError, ValueError):
        pass
    try:
        return open_backend(args.backend, **opts)
    except BackendUnavailable as exc:
        raise Unavailable(str(exc), where=f"backend {args.backend}") from None
    except (BackendError, TypeError, ValueError, OSError) as exc:
        raise UserError(f"cannot open backend {args.backend!r}: {exc}",
                        hint="check --backend-opt values (and --robot-config)") from None


def _run(args) -> int:
    from ..clock import SimClock, WallClock
    from ..tree import RunContext, Status, build_tree
    from ..tree.ticklog import TickLogger
    if args.hz <= 0:
        raise UserError("--hz must be positive", hint="e.g. --hz 10")
    task = _values(args.task)
    spec = _parse(args.file, args, task=task, strict=True)
    extra = sorted(set(task) - set(spec.task))
    if extra:
        from ..tree.errors import did_you_mean
        raise UserError(f"the tree declares no task field {extra[0]!r}", where=args.file,
                        hint=did_you_mean(extra[0], spec.task, "task fields") if spec.task
                        else "the tree declares no `task:` fields")
    clock = SimClock() if args.clock == "sim" else WallClock()
    backend = _backend(args, clock)
    logger = None
    try:
        services = {"profile": args.profile}
        if args.start_pose is not None:
            services["start_pose"] = args.start_pose
        ctx = RunContext(backend=backend, clock=clock, task=_task_values(spec, task), services=services)
        tree = build_tree(spec, ctx)
        if args.log:
            logger = TickLogger(tree, args.log)
        last_report = [clock.now()]

        def progress(t):
            if args.quiet or clock.now() - last_report[0] < 1.0:
                return
            last_report[0] = clock.now()
            tip = t.tip()
            print(f"tick {t.count}  t={clock.now() - start:.1f}s  {t.status.name}"
                  + (f"  at {tip.name}" if tip is not None else ""), file=sys.stderr)
        start = clock.now()
        try:
            status = tree.run(hz=args.hz, max_ticks=args.max_ticks, timeout=args.timeout, on_tick=progress)
        except (UserError, KeyboardInterrupt):
            raise
        except Exception as exc:    # a node's bug: say which node, keep the traceback for -v
            import logging
            logging.getLogger(__name__).debug("tree raised", exc_info=True)
            tip = tree.tip()
            print(f"rll-bt: error: the tree stopped: {type(exc).__name__}: {exc}"
                  + (f" (in or below {tip.name!r})" if tip is not None else "") + "; run with -vv for the traceback",
                  file=sys.stderr)
            return EXIT_FAILURE
    finally:
        if logger is not None:
            logger.close()
        try:
            backend.stop()
        except Exception:
            pass
        backend.close()
    if status is Status.SUCCESS:
        print(f"{spec.name}: SUCCESS after {tree.count} ticks")
        return EXIT_OK
    if status is Status.FAILURE:
        err = tree.error()
        why = f" ({err.code}: {err.message})" if err else ""
        print(f"{spec.name}: FAILURE after {tree.count} ticks{why}")
        return EXIT_FAILURE
    print(f"{spec.name}: stopped while RUNNING after {tree.count} ticks "
          f"({'--max-ticks' if args.max_ticks and tree.count >= args.max_ticks else '--timeout'} reached)")
    return EXIT_FAILURE


def _task_values(spec, task: dict) -> dict:
    """Task fields converted to their declared types (as the loader did)."""
    out = {}
    for k, v in task.items():
        decl = spec.task.get(k)
        out[k] = decl.ptype.from_text(v) if decl is not None and isinstance(v, str) else v
    return out


def _replay(args) -> int:
    from ..tree.ticklog import format_log, read_log
    try:
        header, ticks = read_log(args.log)
    except FileNotFoundError:
        raise UserError("file not found", where=args.log) from None
    except (ValueError, KeyError) as exc:
        raise UserError(str(exc), hint="give a log written by `rll-bt tree run --log`") from None
    for line in format_log(header, ticks, args.first, args.last, args.state):
        print(line)
    return EXIT_OK


def _schema(args) -> int:
    from ..tree.schemagen import schema_text
    text = schema_text(builtin_only=args.builtin)
    if args.output:
        Path(args.output).write_text(text, encoding="utf-8")
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return EXIT_OK
