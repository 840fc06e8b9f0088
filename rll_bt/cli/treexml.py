"""``rll-bt tree export`` and ``rll-bt tree import``: trees as
BehaviorTree.CPP v4 XML, for Groot2 (see :mod:`rll_bt.tree.btcpp`).

    rll-bt tree export --format btcpp trees/deliver.yaml -o deliver.xml
    rll-bt tree export --format btcpp trees/*.yaml -o all_tasks.xml   # one Groot2 project file
    rll-bt tree import deliver.xml -o mytrees/                          # back to YAML files
    rll-bt tree nodes --btcpp > nodes.xml                               # the node catalogue

Exit codes: 0 done, 2 a tree that does not load or XML that cannot be read
(``file:line`` messages), or a file that would be overwritten without --force.
"""
from __future__ import annotations

import sys
from pathlib import Path

from ..errors import UserError


def register(cli) -> None:
    g = cli.group("tree")
    p = g.add_parser("export", help="write trees as BehaviorTree.CPP v4 XML (for Groot2)",
                     description="Write YAML tree files, with every subtree file they include, as one "
                                 "BehaviorTree.CPP v4 XML document with its <TreeNodesModel>, so Groot2 "
                                 "shows and edits them.  The first file is main_tree_to_execute.")
    p.add_argument("files", nargs="+", metavar="FILE")
    p.add_argument("--format", choices=("btcpp",), default="btcpp",
                   help="output format (btcpp: BehaviorTree.CPP 4 XML, the default)")
    p.add_argument("-o", "--output", metavar="OUT.xml", help="write here instead of stdout")
    p.add_argument("-I", "--search-path", action="append", default=[], metavar="DIR",
                   help="also look for subtree files here")
    p.set_defaults(func=_export)

    p = g.add_parser("import", help="read BehaviorTree.CPP v4 XML back into YAML tree files",
                     description="Write every <BehaviorTree> of a BehaviorTree.CPP v4 XML document as a YAML "
                                 "tree file under --output (at the path it was exported from, else "
                                 "<tree_id>.yaml), then check that the trees load.")
    p.add_argument("file", metavar="FILE.xml")
    p.add_argument("-o", "--output", metavar="DIR", default=".", help="folder to write into (default .)")
    p.add_argument("--force", action="store_true", help="overwrite files that exist")
    p.set_defaults(func=_import)


def _export(args) -> int:
    from ..tree.btcpp import export_xml
    for f in args.files:
        if not Path(f).is_file():
            raise UserError("file not found", where=f, hint="give YAML tree files")
    text = export_xml(args.files, search_path=args.search_path)
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as exc:
            raise UserError(f"cannot write: {exc}", where=args.output) from None
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _import(args) -> int:
    from ..tree import parse_tree
    from ..tree.btcpp import import_xml, write_trees
    try:
        text = Path(args.file).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise UserError("file not found", where=args.file) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"cannot read the file: {exc}", where=args.file) from None
    files = import_xml(text, args.file)
    try:
        paths = write_trees(files, args.output, force=args.force)
    except FileExistsError as exc:
        raise UserError("the file exists", where=str(exc),
                        hint="pass --force to overwrite, or another --output") from None
    except OSError as exc:
        raise UserError(f"cannot write: {exc}", where=args.output) from None
    for p in paths:
        print(f"wrote {p}", file=sys.stderr)
    parse_tree(paths[0])            # the main tree and everything it includes load (TreeLoadError: exit 2)
    return 0
