"""The refbox client: what the refbox says, into the knowledge base; what we say, out.

Handles GameState (learns our colour when our team name appears as
team_cyan / team_magenta), ExplorationInfo (2016: type strings <-> light
codes, our zones), MachineInfo (station states, RS colours, slide loads,
released ground truth), MachineReportInfo, OrderInfo and RingInfo, each in
the shape of the profile's message set.  Builds MachineReport,
PrepareMachine and BeaconSignal.

:meth:`RefboxClient.handle` returns :class:`Event` s for the server:
``color``, ``phase``, ``station`` (a state change), ``orders`` (new or
changed orders), ``rings`` (ring costs known/changed).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

from rll_bt import msgs
from rll_bt.rules import CYAN, MAGENTA, PREFIX, Profile

from ..knowledge import model as M
from ..knowledge.kb import REFBOX, KnowledgeBase

log = logging.getLogger("teamserver.links.refbox")

PHASES = {0: "PRE_GAME", 10: "SETUP", 20: "EXPLORATION", 30: "PRODUCTION", 40: "POST_GAME"}
STATES = {0: "INIT", 1: "WAIT_START", 2: "RUNNING", 3: "PAUSED"}
TEAM_VALUE = {CYAN: 0, MAGENTA: 1}
TEAM_NAME = {0: CYAN, 1: MAGENTA}
#: longest stretch (s) the game time is carried forward without a GameState
MAX_EXTRAPOLATION = 5.0
#: states a station is in only after it took a workpiece at its input (PREPARED ->
#: IDLE too: a DS whose PROCESSING report was lost)
FED_STATES = ("PROCESSING", "PROCESSED", "READY-AT-OUTPUT")


@dataclass(frozen=True)
class Event:
    kind: str
    data: Any = None


class RefboxClient:
    """Parses refbox messages for one team; builds its outgoing messages."""

    def __init__(self, kb: KnowledgeBase, team_name: str, *, clock):
        self.kb = kb
        self.profile: Profile = kb.profile
        self.ms = msgs.message_set(self.profile.name)
        self.team_name = team_name
        self.clock = clock
        self.beacon_seq = 0

    # -- derived state ----------------------------------------------------------
    @property
    def color(self) -> str | None:
        return self.kb.get("team_color")

    @property
    def prefix(self) -> str | None:
        c = self.color
        return PREFIX[c] if c else None

    @property
    def phase(self) -> str:
        return self.kb.get("phase", "PRE_GAME")

    @property
    def state(self) -> str:
        return self.kb.get("state", "INIT")

    def game_time(self) -> float:
        """Game time of the current phase now, extrapolated from the last GameState."""
        gt = float(self.kb.get("game_time", 0.0))
        if self.state == "RUNNING":
            since = self.clock.now() - float(self.kb.get("game_time_at", self.clock.now()))
            gt += min(max(since, 0.0), MAX_EXTRAPOLATION)
        return gt

    def production_time(self) -> float | None:
        """Seconds into PRODUCTION, None before it."""
        return self.game_time() if self.phase == "PRODUCTION" else None

    def exploring(self) -> bool:
        """Is the exploration period on (2016: the EXPLORATION phase; 2025:
        the first exploration seconds of PRODUCTION)?"""
        if self.phase == "EXPLORATION":
            return True
        ex = self.profile.phases.exploration_in_production
        return bool(ex) and self.phase == "PRODUCTION" and self.game_time() < ex

    def exploration_left(self) -> float:
        """Seconds of exploration left (0 when none is going on)."""
        if not self.exploring():
            return 0.0
        return self.profile.phases.exploration_deadline - self.game_time()

    def running(self) -> bool:
        return self.state == "RUNNING"

    # -- incoming -------------------------------------------------------------------
    def handle(self, msg) -> list[Event]:
        name = msg.DESCRIPTOR.name
        fn = getattr(self, "_on_" + name, None)
        if fn is None:
            return []
        try:
            return fn(msg) or []
        except (ValueError, KeyError) as exc:
            log.warning("ignoring a %s the client cannot use: %s", name, exc)
            return []

    def _on_GameState(self, gs) -> list[Event]:
        ev = []
        if self.color is None:
            for field_name, color in (("team_cyan", CYAN), ("team_magenta", MAGENTA)):
                if gs.HasField(field_name) and getattr(gs, field_name) == self.team_name:
                    self.kb.set("team_color", color)
                    ev.append(Event("color", color))
        phase, state = PHASES.get(gs.phase, str(gs.phase)), STATES.get(gs.state, str(gs.state))
        gt = gs.game_time.sec + gs.game_time.nsec * 1e-9
        if phase != self.phase or state != self.state:
            ev.append(Event("phase", (phase, state)))
            self.kb.set("phase", phase)
            self.kb.set("state", state)
        self.kb.set("game_time", gt)
        self.kb.set("game_time_at", self.clock.now())
        if self.color is not None:
            pts = gs.points_cyan if self.color == CYAN else gs.points_magenta
            self.kb.meta["points"] = int(pts)
        return ev

    def _on_ExplorationInfo(self, info) -> list[Event]:
        lights_on = self.ms.enum("LightColor")
        types = {}
        for sig in info.signals:
            on = tuple(sorted(lights_on.Name(ls.color) for ls in sig.lights if ls.state != 0))
            types[sig.type] = list(on)
        zones = sorted(int(z.zone) for z in info.zones
                       if self.color is not None and TEAM_NAME[z.team_color] == self.color)
        changed = []
        if types and types != self.kb.get("type_strings"):
            self.kb.set("type_strings", types)
            changed.append("types")
        if zones and zones != self.kb.get("exploration_zones"):
            self.kb.set("exploration_zones", zones)
            changed.append("zones")
        return [Event("exploration_info", tuple(changed))] if changed else []

    def type_string(self, lights: tuple[str, ...]) -> str | None:
        """The 2016 type string announced for a light pattern."""
        want = sorted(lights)
        for t, on in (self.kb.get("type_strings") or {}).items():
            if sorted(on) == want:
                return t
        return None

    def _on_MachineInfo(self, info) -> list[Event]:
        ev = []
        rc = self.ms.enum("RingColor")
        now = self.clock.now()
        for m in info.machines:
            if self.prefix is None or not m.name.startswith(self.prefix + "-"):
                continue
            if m.name not in self.profile.tags:
                continue
            old = self.kb.stations.get(m.name)
            st = M.Station(**(old.to_dict() if old else {"name": m.name}))
            st.ring_colors = tuple(st.ring_colors)
            if m.HasField("state"):
                st.state = m.state
            st.loaded_with = int(m.loaded_with)
            if m.ring_colors:
                st.ring_colors = tuple(rc.Name(c) for c in m.ring_colors)
            if m.HasField("correctly_reported"):
                st.correctly_reported = bool(m.correctly_reported)
            if m.HasField("zone") and int(m.zone) != 0:
                st.zone = int(m.zone)
            if "rotation" in m.DESCRIPTOR.fields_by_name and m.HasField("rotation"):
                st.rotation = int(m.rotation)
            if "status_ss" in m.DESCRIPTOR.fields_by_name and m.status_ss:
                st.shelf = tuple(f"{p.shelf},{p.slot}" for p in m.status_ss if p.is_filled)
                st.stored = tuple(f"{p.shelf},{p.slot}={p.description}" for p in m.status_ss
                                  if p.is_filled and p.HasField("description"))
            if old is not None and old.state != st.state:
                st.since = now
                if st.state in FED_STATES or (old.state == "PREPARED" and st.state in (
                        "IDLE", "WAIT-IDLE")):
                    st.fed_at = now
                ev.append(Event("station", (m.name, old.state, st.state)))
            elif old is None:
                st.since = now
                ev.append(Event("station", (m.name, None, st.state)))
            if old is None or old.to_dict() != st.to_dict():
                self.kb.save_station(st)
            self._ground_truth(st, old)
        return ev

    def _ground_truth(self, st: M.Station, old: M.Station | None) -> None:
        """Zone/rotation in MachineInfo are the refbox's truth: fuse them as such."""
        if st.zone is not None and (old is None or old.zone != st.zone):
            self.kb.add_observation(M.Observation(st.name, M.ZONE, st.zone, 0.999, REFBOX,
                                                  self.clock.now()))
        if st.rotation is not None and (old is None or old.rotation != st.rotation):
            self.kb.add_observation(M.Observation(
                st.name, M.ORIENTATION, self.profile.discretise_rotation(st.rotation), 0.999,
                REFBOX, self.clock.now()))

    def _on_MachineReportInfo(self, info) -> list[Event]:
        if self.color is None or TEAM_NAME.get(info.team_color) != self.color:
            return []
        names = sorted(info.reported_machines)
        if names != self.kb.get("refbox_reported"):
            self.kb.set("refbox_reported", names)
        return []

    def _on_OrderInfo(self, info) -> list[Event]:
        bc, rc, cc = self.ms.enum("BaseColor"), self.ms.enum("RingColor"), self.ms.enum("CapColor")
        changed = []
        for o in info.orders:
            delivered = (o.quantity_delivered_cyan if self.color != MAGENTA
                         else o.quantity_delivered_magenta)
            order = M.Order(
                id=int(o.id), complexity=int(o.complexity), base=bc.Name(o.base_color),
                rings=tuple(rc.Name(r) for r in o.ring_colors), cap=cc.Name(o.cap_color),
                quantity=int(o.quantity_requested), delivered=int(delivered),
                begin=float(o.delivery_period_begin), end=float(o.delivery_period_end),
                gate=int(o.delivery_gate) if o.HasField("delivery_gate") else 0,
                competitive=bool(getattr(o, "competitive", False)))
            old = self.kb.orders.get(order.id)
            if old is None or old.to_dict() != order.to_dict():
                self.kb.save_order(order)
                changed.append((order.id, old is None))
        return [Event("orders", tuple(changed))] if changed else []

    def _on_RingInfo(self, info) -> list[Event]:
        rc = self.ms.enum("RingColor")
        costs = {rc.Name(r.ring_color): int(r.raw_material) for r in info.rings}
        if costs and costs != self.kb.get("ring_costs"):
            self.kb.set("ring_costs", costs)
            return [Event("rings", costs)]
        return []

    # -- outgoing ---------------------------------------------------------------------
    def machine_report(self, entries: list[dict]):
        """MachineReport of ``entries`` ({name, type?, zone?, rotation?})."""
        rep = self.ms.MachineReport(team_color=TEAM_VALUE[self.color])
        for e in entries:
            me = rep.machines.add(name=e["name"])
            if e.get("type") is not None:
                me.type = e["type"]
            if e.get("zone") is not None:
                me.zone = int(e["zone"])
            if e.get("rotation") is not None and "rotation" in me.DESCRIPTOR.fields_by_name:
                me.rotation = int(e["rotation"])
        return rep

    def prepare_machine(self, prepare: dict):
        """PrepareMachine from a task's ``prepare`` dict (see the planning domain)."""
        pm = self.ms.PrepareMachine(team_color=TEAM_VALUE[self.color], machine=prepare["machine"])
        if "bs" in prepare:
            pm.instruction_bs.side = self.ms.enum("MachineSide").Value(prepare["bs"]["side"])
            pm.instruction_bs.color = self.ms.enum("BaseColor").Value(prepare["bs"]["color"])
        elif "rs" in prepare:
            pm.instruction_rs.ring_color = self.ms.enum("RingColor").Value(
                prepare["rs"]["ring_color"])
        elif "cs" in prepare:
            op_enum = "CsOp" if "CsOp" in self.ms.enums else "CSOp"
            pm.instruction_cs.operation = self.ms.enum(op_enum).Value(prepare["cs"]["operation"])
        elif "ss" in prepare:
            ss = prepare["ss"]
            pm.instruction_ss.operation = self.ms.enum("SSOp").Value(ss["operation"])
            pm.instruction_ss.shelf, pm.instruction_ss.slot = int(ss["shelf"]), int(ss["slot"])
        elif "ds" in prepare:
            ds = prepare["ds"]
            if "order_id" in pm.instruction_ds.DESCRIPTOR.fields_by_name:
                pm.instruction_ds.order_id = int(ds.get("order_id", 0))
            else:
                pm.instruction_ds.gate = int(ds.get("gate", 1))
        else:
            raise ValueError(f"prepare without an instruction: {prepare}")
        if "sent_at" in pm.DESCRIPTOR.fields_by_name:
            pm.sent_at = int(self.clock.epoch())
        return pm

    def beacon(self, number: int, peer_name: str = "teamserver"):
        """BeaconSignal of the team server itself (``number`` is its jersey)."""
        self.beacon_seq += 1
        t = self.clock.epoch()
        b = self.ms.BeaconSignal(seq=self.beacon_seq, number=number, team_name=self.team_name,
                                 peer_name=peer_name)
        b.time.sec, b.time.nsec = int(t), int((t % 1) * 1e9)
        if self.color is not None:
            b.team_color = TEAM_VALUE[self.color]
        return b
