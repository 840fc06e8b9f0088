"""Game state to ``llsf_msgs`` messages and incoming messages to plain values.

Every message is built from the profile's message set
(``msgs.message_set(profile.name)``); fields a set does not have are left
out (e.g. 2016's ``exploration_type_state`` vs today's
``exploration_rotation_state``), so another set plugs in without changes
here beyond what its rules add.
"""
from __future__ import annotations

import math
import random

from rll_bt import __version__
from rll_bt import msgs as M
from rll_bt.rules import CYAN, MAGENTA, TEAMS, machine_team

from .exploration2016 import ReportEntry
from .stations import BSInstruction, CSInstruction, DSInstruction, RSInstruction, SSInstruction

REFBOX_TEAM, REFBOX_PEER, REFBOX_NUMBER = "LLSF", "RefBox", 0
#: largest protobuf that fits a 1024-byte AES-128-CBC datagram (8 header + 16 IV +
#: PKCS#7-padded 4-byte message header and protobuf)
MAX_ENCRYPTED_PROTOBUF = 987


def set_enum(msg, field: str, name: str) -> bool:
    """Set enum ``field`` of ``msg`` by value name; False if the set lacks the field or value."""
    fd = msg.DESCRIPTOR.fields_by_name.get(field)
    if fd is None or fd.enum_type is None or name not in fd.enum_type.values_by_name:
        return False
    value = fd.enum_type.values_by_name[name].number
    if fd.is_repeated:
        getattr(msg, field).append(value)
    else:
        setattr(msg, field, value)
    return True


def enum_name(msg, field: str) -> str | None:
    """Name of enum ``field``'s value (None when unset or unknown)."""
    fd = msg.DESCRIPTOR.fields_by_name.get(field)
    if fd is None or fd.enum_type is None or not msg.HasField(field):
        return None
    v = fd.enum_type.values_by_number.get(getattr(msg, field))
    return v.name if v else None


def has_field(msg, field: str) -> bool:
    return field in msg.DESCRIPTOR.fields_by_name


def set_time(t, seconds: float) -> None:
    """Fill an ``llsf_msgs.Time`` with ``seconds`` (sec, nsec)."""
    sec = math.floor(seconds)
    t.sec = int(sec)
    t.nsec = int(round((seconds - sec) * 1e9)) % 1_000_000_000


class Messages:
    """Builds the refbox's outgoing messages for one message set."""

    def __init__(self, message_set: str):
        self.ms = M.message_set(message_set)
        self.seq = 0

    def new(self, name: str):
        return self.ms.get(name)()

    # -- outgoing ---------------------------------------------------------------
    def beacon(self, epoch: float):
        b = self.new("BeaconSignal")
        set_time(b.time, epoch)
        self.seq += 1
        b.seq = self.seq
        b.number, b.team_name, b.peer_name = REFBOX_NUMBER, REFBOX_TEAM, REFBOX_PEER
        return b

    def version_info(self):
        v = self.new("VersionInfo")
        parts = [int(p) if p.isdigit() else 0 for p in __version__.split(".")[:3]]
        parts += [0] * (3 - len(parts))
        v.version_major, v.version_minor, v.version_micro = parts
        v.version_string = f"rll-bt simulated refbox {__version__} ({self.ms.name})"
        return v

    def game_state(self, game):
        g = self.new("GameState")
        set_time(g.game_time, game.game_time)
        set_enum(g, "state", game.state)
        set_enum(g, "phase", game.phase)
        for color, pf, tf in ((CYAN, "points_cyan", "team_cyan"),
                              (MAGENTA, "points_magenta", "team_magenta")):
            setattr(g, pf, game.points(color))
            if game.teams[color]:
                setattr(g, tf, game.teams[color])
        return g

    def robot_info(self, game, with_pose: bool = True):
        ri = self.new("RobotInfo")
        for r in game.robots.listed():
            rm = ri.robots.add()
            rm.name, rm.team, rm.number, rm.host = r.name, r.team, r.number, str(r.host)
            set_enum(rm, "team_color", r.team_color)
            set_time(rm.last_seen, r.last_seen_epoch)
            set_enum(rm, "state", r.state)
            if with_pose and r.pose is not None:
                set_time(rm.pose.timestamp, r.last_seen_epoch)
                rm.pose.x, rm.pose.y, rm.pose.ori = r.pose
        return ri

    def exploration_info(self, game, rng: random.Random):
        ei = self.new("ExplorationInfo")
        ex = game.exploration
        for type_string, lights in ex.signals(rng):
            s = ei.signals.add()
            s.type = type_string
            self._lights(s.lights, lights)
        for color, zones in ex.zone_lists().items():
            for z in zones:
                ez = ei.zones.add()
                ez.zone = z
                set_enum(ez, "team_color", color)
        return ei

    def machine_report_info(self, game, team: str):
        mri = self.new("MachineReportInfo")
        set_enum(mri, "team_color", team)
        for m in game.exploration.reported(team):
            mri.reported_machines.append(m)
        if has_field(mri, "reported_types"):
            for r in game.exploration.type_feedback(team):
                f = mri.reported_types.add()
                f.type, f.zone = r.type, r.zone
                if r.machine:
                    f.name = r.machine
                    set_enum(f, "team_color", machine_team(r.machine))
        return mri

    def order_info(self, game):
        oi = self.new("OrderInfo")
        for o in game.active_orders():
            om = oi.orders.add()
            om.id = o.id
            set_enum(om, "complexity", f"C{o.complexity}")
            set_enum(om, "base_color", o.base)
            for r in o.rings:
                set_enum(om, "ring_colors", r)
            set_enum(om, "cap_color", o.cap)
            om.quantity_requested = o.quantity
            om.quantity_delivered_cyan = o.delivered[CYAN]
            om.quantity_delivered_magenta = o.delivered[MAGENTA]
            om.delivery_period_begin, om.delivery_period_end = o.begin, o.end
            if has_field(om, "delivery_gate"):
                om.delivery_gate = o.gate
            if has_field(om, "competitive"):
                om.competitive = o.competitive
            if has_field(om, "unconfirmed_deliveries"):
                for d in game.pending_deliveries:
                    if d.order == o.id:
                        u = om.unconfirmed_deliveries.add()
                        u.id = d.id
                        set_enum(u, "team", d.team)
                        set_time(u.delivery_time, d.game_time)
        return oi

    def ring_info(self, game):
        ri = self.new("RingInfo")
        for color in sorted(game.ring_costs):
            r = ri.rings.add()
            set_enum(r, "ring_color", color)
            r.raw_material = game.ring_costs[color]
        return ri

    def machine_info(self, game, team: str | None):
        """MachineInfo of ``team``'s machines; for None every machine with what the
        refbox tells its controllers only (net.clp's restricted info): where each
        stands, zone and rotation, from the start."""
        mi = self.new("MachineInfo")
        if team is not None:
            set_enum(mi, "team_color", team)
        for name in game.profile.machines(team):
            m = mi.machines.add()
            if team is None and has_field(m, "rotation"):
                pl = game.layout[name]
                m.zone, m.rotation = pl.zone, int(pl.rotation_deg) % 360
            self._machine(m, game, name)
        if team is not None:
            _fit_storage_notes(mi)
        return mi

    def _machine(self, m, game, name: str) -> None:
        st = game.stations[name]
        m.name, m.type, m.state = name, name[2:4], st.state
        set_enum(m, "team_color", st.team)
        if has_field(m, "input_tag"):
            m.input_tag, m.output_tag = game.profile.tag_ids(name)
        self._lights(m.lights, st.lights)
        # zone (Zone enum values are the zone numbers), rotation and report states
        for f, value in game.exploration.report_fields(st.team, name).items():
            if not has_field(m, f):
                continue
            if isinstance(value, str):
                set_enum(m, f, value)
            else:
                setattr(m, f, value)
        if name[2:4] == "RS":
            for c in game.rs_colors(name):
                set_enum(m, "ring_colors", c)
            m.loaded_with = max(0, st.slide_loaded)
        if name[2:4] == "SS" and has_field(m, "status_ss"):
            for place in st.status():            # all 48 places, as the refbox
                si = m.status_ss.add()
                si.shelf, si.slot, si.is_filled = place.shelf, place.slot, place.filled
                if place.description:
                    si.description = place.description

    @staticmethod
    def _lights(repeated, lights: dict) -> None:
        for color in ("RED", "YELLOW", "GREEN"):
            ls = repeated.add()
            set_enum(ls, "color", color)
            set_enum(ls, "state", lights.get(color, "OFF"))

    def attention(self, text: str, team: str | None, time_to_show: float = 10.0):
        a = self.new("AttentionMessage")
        a.message = text[:400]
        a.time_to_show = float(time_to_show)
        if team in TEAMS:
            set_enum(a, "team_color", team)
        return a

    # -- incoming -----------------------------------------------------------------
    @staticmethod
    def report(msg) -> tuple[str | None, list[ReportEntry]]:
        """(team colour, entries) of a MachineReport."""
        team = enum_name(msg, "team_color")
        entries = []
        for e in msg.machines:
            name = e.name if e.HasField("name") and e.name else None
            etype = e.type if e.HasField("type") and e.type else None
            zone = e.zone if e.HasField("zone") else None
            rot = e.rotation if has_field(e, "rotation") and e.HasField("rotation") else None
            entries.append(ReportEntry(name, etype, zone, rot))
        return team, entries

    @staticmethod
    def prepare(msg, machine_kind: str):
        """The instruction of a PrepareMachine for a ``machine_kind`` ("BS", ...) station,
        None when the message carries none for that kind (the station breaks)."""
        field = {"BS": "instruction_bs", "RS": "instruction_rs", "CS": "instruction_cs",
                 "DS": "instruction_ds", "SS": "instruction_ss"}.get(machine_kind)
        if field is None or not has_field(msg, field) or not msg.HasField(field):
            return None
        i = getattr(msg, field)
        if machine_kind == "BS":
            return BSInstruction(enum_name(i, "side") or "?", enum_name(i, "color") or "?")
        if machine_kind == "RS":
            return RSInstruction(enum_name(i, "ring_color") or "?")
        if machine_kind == "CS":
            return CSInstruction(enum_name(i, "operation") or "?")
        if machine_kind == "SS":
            desc = i.wp_description if i.HasField("wp_description") else None
            return SSInstruction(enum_name(i, "operation") or "?", i.shelf, i.slot, desc)
        gate = i.gate if has_field(i, "gate") and i.HasField("gate") else 0
        order = i.order_id if has_field(i, "order_id") and i.HasField("order_id") else None
        return DSInstruction(gate, order)


def sent_at(msg) -> float | None:
    """A PrepareMachine's ``sent_at`` (Unix seconds), None when absent (or the set lacks it)."""
    return float(msg.sent_at) if has_field(msg, "sent_at") and msg.HasField("sent_at") else None


def _fit_storage_notes(mi) -> None:
    """Drop storage descriptions (last first) until ``mi`` fits one encrypted datagram; a
    full shelf of 48 places with long notes would not."""
    notes = [si for m in mi.machines for si in m.status_ss if si.HasField("description")] \
        if mi.machines and has_field(mi.machines[0], "status_ss") else []
    while notes and mi.ByteSize() > MAX_ENCRYPTED_PROTOBUF:
        notes.pop().ClearField("description")
