"""Draw a checked tree: text (``--ascii``), Graphviz DOT text (``--dot``) and
PNG drawn with matplotlib (``--png``; no Graphviz program needed)."""
from __future__ import annotations

from pathlib import Path

from .ports import Const, Key
from .spec import NodeSpec, TreeSpec

_KIND_STYLE = {   # face colour, edge colour
    "composite": ("#dbe9f6", "#2f6690"),
    "decorator": ("#efe3f7", "#6a3d9a"),
    "subtree": ("#fff2cc", "#b7950b"),
    "action": ("#e2f0d9", "#38761d"),
    "condition": ("#fde2cf", "#b45f06"),
}


def _args(ns: NodeSpec, width: int = 60) -> str:
    parts = []
    for k, b in ns.ports.items():
        if ns.type == "subtree" and k == "file":
            continue
        text = b.source if b.source is not None else repr(getattr(b, "value", b))
        if isinstance(b, Key) and not text.startswith("$"):
            text = f"$bb.{b.key}"
        parts.append(f"{k}={text}")
    s = ", ".join(parts)
    return s if len(s) <= width else s[:width - 3] + "..."


def _label(ns: NodeSpec) -> str:
    if ns.type == "subtree":
        return f"subtree {ns.name!r} <- {ns.file}"
    return ns.type if ns.name == ns.type else f"{ns.type} {ns.name!r}"


def ascii_tree(spec: TreeSpec, locations: bool = False) -> str:
    """The tree as indented text with box-drawing branches."""
    lines = [f"{spec.name}  ({spec.file})"]
    for name, decl in spec.outputs.items():
        lines.append(f"  output {name}: {decl.ptype.name} -> {spec.output_keys[name]}"
                     + (f"  ({decl.doc})" if decl.doc else ""))

    def walk(ns: NodeSpec, prefix: str, last: bool, slot: str | None):
        branch = "└── " if last else "├── "
        tag = f"[{slot}] " if slot and slot not in ("children", "child", "root") else ""
        args = _args(ns)
        line = prefix + branch + tag + _label(ns) + (f"  ({args})" if args else "")
        if locations:
            line += f"  @{ns.loc}"
        lines.append(line)
        kids = [(s, c) for s, cs in ns.slots.items() for c in cs]
        for i, (s, c) in enumerate(kids):
            walk(c, prefix + ("    " if last else "│   "), i == len(kids) - 1, s)
    walk(spec.root, "", True, None)
    return "\n".join(lines)


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"')


def dot_tree(spec: TreeSpec) -> str:
    """Graphviz DOT text for the tree."""
    out = [f'digraph "{_esc(spec.name)}" {{', "  rankdir=TB;", '  node [fontname="Helvetica", fontsize=10];']
    counter = [0]

    def walk(ns: NodeSpec) -> str:
        me = f"n{counter[0]}"
        counter[0] += 1
        face, edge = _KIND_STYLE.get(ns.kind, ("#ffffff", "#000000"))
        shape = {"composite": "box", "decorator": "octagon", "subtree": "folder",
                 "condition": "ellipse"}.get(ns.kind, "box")
        style = "filled" if ns.kind != "action" else "filled,rounded"
        label = _esc(_label(ns))
        args = _args(ns, 40)
        if args:
            label += "\\n" + _esc(args)
        out.append(f'  {me} [label="{label}", shape={shape}, style="{style}", fillcolor="{face}", '
                   f'color="{edge}"];')
        for slot, kids in ns.slots.items():
            for c in kids:
                cid = walk(c)
                attr = f' [label="{slot}", fontsize=8]' if slot not in ("children", "child", "root") else ""
                out.append(f"  {me} -> {cid}{attr};")
        return me
    walk(spec.root)
    out.append("}")
    return "\n".join(out)


def png_tree(spec: TreeSpec, path: str | Path, dpi: int = 110) -> Path:
    """Draw the tree to a PNG with matplotlib."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyBboxPatch

    pos: dict[int, tuple[float, int]] = {}
    items: list[tuple[int, NodeSpec, int | None]] = []
    next_x = [0.0]

    def layout(ns: NodeSpec, depth: int, parent: int | None) -> float:
        me = len(items)
        items.append((me, ns, parent))
        kids = ns.children()
        if not kids:
            x = next_x[0]
            next_x[0] += 1.0
        else:
            xs = [layout(c, depth + 1, me) for c in kids]
            x = (xs[0] + xs[-1]) / 2.0
        pos[me] = (x, depth)
        return x
    layout(spec.root, 0, None)
    width = max(next_x[0], 1.0)
    depth = max(d for _, d in pos.values()) + 1
    fig = Figure(figsize=(max(4.0, 1.9 * width), max(2.5, 1.15 * depth + 0.6)), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.01, 0.01, 0.98, 0.92))
    ax.set_xlim(-0.6, width - 0.4)
    ax.set_ylim(-(depth - 0.4), 0.6)
    ax.axis("off")
    fig.suptitle(f"{spec.name}  ({spec.file})", fontsize=10)
    for me, _ns, parent in items:
        x, d = pos[me]
        if parent is not None:
            px, pd = pos[parent]
            ax.plot([px, x], [-pd - 0.22, -d + 0.22], color="#888888", linewidth=0.8, zorder=1)
    for me, ns, _parent in items:
        x, d = pos[me]
        face, edge = _KIND_STYLE.get(ns.kind, ("#ffffff", "#000000"))
        ax.add_patch(FancyBboxPatch((x - 0.44, -d - 0.22), 0.88, 0.44, boxstyle="round,pad=0.02,rounding_size=0.08",
                                    facecolor=face, edgecolor=edge, linewidth=1.0, zorder=2))
        title = ns.type if ns.type != "subtree" else f"subtree: {Path(ns.file or '').name}"
        sub = ns.name if ns.name != ns.type else _args(ns, 22)
        ax.text(x, -d + 0.07, title, ha="center", va="center", fontsize=7, weight="bold", zorder=3)
        if sub:
            ax.text(x, -d - 0.09, sub if len(sub) <= 24 else sub[:21] + "...", ha="center", va="center",
                    fontsize=6.5, zorder=3)
    out = Path(path)
    fig.savefig(out, format="png")
    return out


__all__ = ["ascii_tree", "dot_tree", "png_tree", "Const"]
