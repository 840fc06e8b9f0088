"""``rll-bt teamserver status``: the state database as tables (read-only).

Robots, open and recent tasks, orders and known machines, read from a
running (or stopped) server's SQLite file without disturbing it.
"""
from __future__ import annotations

from rll_bt import rules
from rll_bt.errors import UserError

from .exploration.symmetry import consistent_set
from .knowledge import model as M
from .knowledge.kb import KnowledgeBase
from .knowledge.store import Store


def table(headers: list[str], rows: list[list]) -> str:
    """A plain text table, columns as wide as their widest cell."""
    cells = [[str(h) for h in headers]] + [["-" if c is None else str(c) for c in r]
                                           for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def load(path: str) -> KnowledgeBase:
    store = Store(path, readonly=True)
    name = store.get_meta("profile")
    if name is None:
        raise UserError("the state database names no rules profile", where=path)
    return KnowledgeBase.load(rules.profile(name), store)


def render(kb: KnowledgeBase, recent: int = 10) -> str:
    out = []
    meta = kb.meta
    out.append(f"profile {kb.profile.name}   colour {meta.get('team_color') or '?'}   "
               f"phase {meta.get('phase', '?')} {meta.get('state', '')}   "
               f"game time {float(meta.get('game_time', 0.0)):.0f} s   "
               f"observations {kb.observation_count}")
    out.append("\nRobots")
    out.append(table(["#", "name", "status", "pose", "task", "holding"], [
        [r.number, r.name, r.status,
         None if r.pose is None else f"({r.pose[0]:.2f}, {r.pose[1]:.2f})", r.task_id, r.holding]
        for r in sorted(kb.robots.values(), key=lambda r: r.number)]))
    tasks = sorted(kb.tasks.values(), key=lambda t: t.id)
    shown = [t for t in tasks if t.state in M.OPEN_STATES]
    shown += [t for t in tasks if t.state not in M.OPEN_STATES][-recent:]
    out.append(f"\nTasks ({len(tasks)} in all: open ones and the last {recent} closed)")
    out.append(table(["id", "kind", "target", "state", "robot", "product", "error"], [
        [t.id, t.kind, t.params.get("machine") or t.params.get("zone"), t.state, t.robot,
         t.product, t.error] for t in sorted(shown, key=lambda t: t.id)]))
    out.append("\nOrders")
    out.append(table(["id", "C", "base", "rings", "cap", "qty", "delivered", "window", "products"], [
        [o.id, o.complexity, o.base.replace("BASE_", ""),
         " ".join(r.replace("RING_", "") for r in o.rings) or None, o.cap.replace("CAP_", ""),
         o.quantity, o.delivered, f"{o.begin:.0f}-{o.end:.0f}",
         " ".join(f"{p.id}:{p.state}" for p in kb.products.values() if p.order_id == o.id)
         or None]
        for o in sorted(kb.orders.values(), key=lambda o: o.id)]))
    cs = consistent_set(kb.profile, kb.machines)
    out.append("\nKnown machines")
    rows = []
    for name in sorted(kb.profile.tags):
        g = cs.machines.get(name)
        st = kb.stations.get(name)
        if (g is None or g.zone is None) and st is None:
            continue
        rows.append([name, None if g is None or g.zone is None else kb.profile.zone_name(g.zone),
                     None if g is None or g.zone is None else f"{g.zone_confidence:.2f}",
                     None if g is None or g.light is None else "+".join(g.light),
                     None if g is None else g.orientation,
                     ", ".join(f"{k}={v}" for k, v in kb.reported.get(name, {}).items())
                     or None, None if st is None else st.state])
    out.append(table(["machine", "zone", "conf", "light", "rotation", "reported", "state"], rows))
    return "\n".join(out)
