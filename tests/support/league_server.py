"""An AgentTask team server of the league, written here from the field tables
alone (reference/league-interfaces.md, refbox-protocol.md), independent of
rll_bt: its own message classes (descriptor_pb2, package ``league``), its
own protobuf_comm framing and AES-128-CBC (hashlib and raw AES), its own
sockets.  It drives robots that connect to it over TCP the way the league's
simulator's robots do (AgentTask out, BeaconSignal and echoed AgentTask in)
and talks to the refbox over UDP (GameState, OrderInfo and MachineInfo in,
PrepareMachine out on its encrypted team channel).

Non-blocking: call :meth:`LeagueServer.poll` often (the tests do it from
the game's loop)."""
from __future__ import annotations

import os
import socket
import struct
import types

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

from tests.support.comm import aes, hand_key, pkcs7

F = descriptor_pb2.FieldDescriptorProto
REQ, OPT, REP = F.LABEL_REQUIRED, F.LABEL_OPTIONAL, F.LABEL_REPEATED
U32, U64, I64, BOOL, STR, FLT, MSG, ENUM = (F.TYPE_UINT32, F.TYPE_UINT64, F.TYPE_INT64, F.TYPE_BOOL, F.TYPE_STRING,
                                            F.TYPE_FLOAT, F.TYPE_MESSAGE, F.TYPE_ENUM)
PKG = "league"


def _enum(container, name, values):
    e = container.enum_type.add(name=name)
    for n, v in values:
        e.value.add(name=n, number=v)


def _msg(fdp, name, fields, comp=None, enums=()):
    m = fdp.message_type.add(name=name)
    for ename, values in enums:
        _enum(m, ename, values)
    if comp is not None:
        _enum(m, "CompType", [("COMP_ID", comp[0]), ("MSG_TYPE", comp[1])])
    for fname, number, ftype, label, *tname in fields:
        f = m.field.add(name=fname, number=number, type=ftype, label=label)
        if tname:
            f.type_name = f".{PKG}.{tname[0]}"
    return m


def build():
    fdp = descriptor_pb2.FileDescriptorProto(name="league.proto", package=PKG, syntax="proto2")
    _enum(fdp, "Team", [("CYAN", 0), ("MAGENTA", 1)])
    _enum(fdp, "BaseColor", [("BASE_RED", 1), ("BASE_BLACK", 2), ("BASE_SILVER", 3), ("BASE_CLEAR", 4)])
    _enum(fdp, "RingColor", [("RING_BLUE", 1), ("RING_GREEN", 2), ("RING_ORANGE", 3), ("RING_YELLOW", 4)])
    _enum(fdp, "CapColor", [("CAP_BLACK", 1), ("CAP_GREY", 2)])
    _msg(fdp, "Time", [("sec", 1, I64, REQ), ("nsec", 2, I64, REQ)])
    _msg(fdp, "Pose2D", [("timestamp", 1, MSG, REQ, "Time"), ("x", 2, FLT, REQ), ("y", 3, FLT, REQ),
                         ("ori", 4, FLT, REQ)])
    # AgentTask and its parts, as the league's field table gives them
    _msg(fdp, "Move", [("waypoint", 1, STR, REQ), ("machine_point", 2, STR, OPT)])
    _msg(fdp, "Retrieve", [("machine_id", 1, STR, REQ), ("machine_point", 2, STR, REQ)])
    _msg(fdp, "Deliver", [("machine_id", 1, STR, REQ), ("machine_point", 2, STR, REQ)])
    _msg(fdp, "BufferStation", [("machine_id", 1, STR, REQ), ("shelf_number", 2, U32, REQ)])
    _msg(fdp, "ExploreWaypoint", [("machine_id", 1, STR, REQ), ("machine_point", 2, STR, REQ),
                                  ("waypoint", 3, STR, REQ)])
    _msg(fdp, "WorkpieceDescription", [("base_color", 3, ENUM, REQ, "BaseColor"),
                                       ("ring_colors", 4, ENUM, REP, "RingColor"),
                                       ("cap_color", 5, ENUM, OPT, "CapColor")], comp=(8000, 510))
    _msg(fdp, "AgentTask", [
        ("team_color", 1, ENUM, REQ, "Team"), ("task_id", 2, U32, REQ), ("robot_id", 3, U32, REQ),
        ("move", 4, MSG, OPT, "Move"), ("retrieve", 5, MSG, OPT, "Retrieve"), ("deliver", 6, MSG, OPT, "Deliver"),
        ("buffer", 7, MSG, OPT, "BufferStation"), ("explore_machine", 8, MSG, OPT, "ExploreWaypoint"),
        ("workpiece_description", 9, MSG, OPT, "WorkpieceDescription"), ("order_id", 10, U32, OPT),
        ("cancel_task", 11, BOOL, OPT), ("pause_task", 12, BOOL, OPT), ("successful", 13, BOOL, OPT),
        ("canceled", 14, BOOL, OPT), ("error_code", 15, U32, OPT)], comp=(8000, 502), enums=[(
            "ErrorCode", [("NO_ERROR", 0), ("UNKNOWN", 1), ("WRONG_TEAM", 101), ("WRONG_ROBOT", 102),
                          ("INVALID_TARGET", 103), ("TASK_NOT_SUPPORTED", 104), ("NOT_AT_POSITION", 105),
                          ("UNABLE_TO_MOVE_TO_TARGET", 201), ("NO_WORKPIECE_FOUND", 202), ("MPS_NOT_FOUND", 203),
                          ("WORKPIECE_SENSOR_DISAGREEMENT", 204), ("ABORTED_DUE_TO_UNEXPECTED_COLLISION", 205),
                          ("GRASPING_FAILED", 206), ("WORKPIECE_ALREADY_IN_GRIPPER", 207),
                          ("NO_WORKPIECE_IN_GRIPPER", 208), ("MACHINE_POINT_OCCUPIED", 209),
                          ("INTERNAL_ERROR", 220), ("NO_PATH_FOUND", 300)])])
    _msg(fdp, "FinishedTask", [("TaskId", 1, U32, REQ), ("successful", 2, BOOL, REQ)])
    _msg(fdp, "BeaconSignal", [
        ("time", 1, MSG, REQ, "Time"), ("seq", 2, U64, REQ), ("number", 8, U32, REQ), ("team_name", 4, STR, REQ),
        ("peer_name", 5, STR, REQ), ("team_color", 6, ENUM, OPT, "Team"), ("pose", 7, MSG, OPT, "Pose2D"),
        ("task", 9, MSG, OPT, "AgentTask"), ("finished_tasks", 10, MSG, REP, "FinishedTask")], comp=(2000, 1))
    # what this team server reads of the refbox (only the fields it uses; all optional)
    _msg(fdp, "GameState", [("game_time", 1, MSG, OPT, "Time"), ("state", 3, U32, OPT), ("phase", 4, U32, OPT),
                            ("points_cyan", 5, U32, OPT), ("team_cyan", 6, STR, OPT),
                            ("points_magenta", 8, U32, OPT), ("team_magenta", 9, STR, OPT)], comp=(2000, 20))
    _msg(fdp, "Order", [("id", 1, U32, OPT), ("complexity", 2, U32, OPT), ("base_color", 3, U32, OPT),
                        ("ring_colors", 4, U32, REP), ("cap_color", 5, U32, OPT),
                        ("quantity_requested", 6, U32, OPT), ("delivery_period_begin", 9, U32, OPT),
                        ("delivery_period_end", 10, U32, OPT), ("competitive", 13, BOOL, OPT)], comp=(2000, 42))
    _msg(fdp, "OrderInfo", [("orders", 1, MSG, REP, "Order")], comp=(2000, 41))
    _msg(fdp, "Machine", [("name", 1, STR, OPT), ("type", 2, STR, OPT), ("state", 3, STR, OPT),
                          ("team_color", 10, U32, OPT), ("zone", 11, U32, OPT), ("rotation", 12, U32, OPT)],
         comp=(2000, 12))
    _msg(fdp, "MachineInfo", [("machines", 1, MSG, REP, "Machine"), ("team_color", 2, U32, OPT)], comp=(2000, 13))
    # what it sends the refbox
    _msg(fdp, "PrepareInstructionBS", [("side", 1, U32, REQ), ("color", 2, U32, REQ)])
    _msg(fdp, "PrepareInstructionDS", [("order_id", 2, U32, REQ)])
    _msg(fdp, "PrepareInstructionRS", [("ring_color", 1, U32, REQ)])
    _msg(fdp, "PrepareInstructionCS", [("operation", 1, U32, REQ)])
    _msg(fdp, "PrepareMachine", [
        ("team_color", 1, ENUM, REQ, "Team"), ("machine", 2, STR, REQ),
        ("instruction_bs", 4, MSG, OPT, "PrepareInstructionBS"),
        ("instruction_ds", 5, MSG, OPT, "PrepareInstructionDS"),
        ("instruction_rs", 6, MSG, OPT, "PrepareInstructionRS"),
        ("instruction_cs", 7, MSG, OPT, "PrepareInstructionCS")],
        comp=(2000, 101))
    pool = descriptor_pool.DescriptorPool()
    pool.Add(fdp)
    ns = types.SimpleNamespace()
    for m in fdp.message_type:
        setattr(ns, m.name, message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{PKG}.{m.name}")))
    ns.by_type = {}
    for m in fdp.message_type:
        ct = [e for e in m.enum_type if e.name == "CompType"]
        if ct:
            vals = {v.name: v.number for v in ct[0].value}
            ns.by_type[(vals["COMP_ID"], vals["MSG_TYPE"])] = getattr(ns, m.name)
    ns.error_name = {v.number: v.name for v in fdp.message_type[[m.name for m in fdp.message_type].index(
        "AgentTask")].enum_type[0].value}
    return ns


L = build()
BASE = {"BASE_RED": 1, "BASE_BLACK": 2, "BASE_SILVER": 3}
CAP = {1: "CAP_BLACK", 2: "CAP_GREY"}


def comp_type(msg) -> tuple[int, int]:
    vals = {v.name: v.number for v in msg.DESCRIPTOR.enum_types_by_name["CompType"].values}
    return vals["COMP_ID"], vals["MSG_TYPE"]


def frame(msg, key: bytes | None = None) -> bytes:
    """A protobuf_comm v2 frame: plain, or AES-128-CBC (cipher 2) with a random IV."""
    body = struct.pack(">HH", *comp_type(msg)) + msg.SerializeToString()
    if key is None:
        return struct.pack(">BBBBI", 2, 0, 0, 0, len(body)) + body
    iv = os.urandom(16)
    ct = aes(key, iv, pkcs7(body))
    return struct.pack(">BBBBI", 2, 2, 0, 0, 16 + len(ct)) + iv + ct


def unframe(data: bytes, key: bytes | None = None):
    """The message of one frame, or None when its type is not one this server knows."""
    version, cipher, _r1, _r2, size = struct.unpack(">BBBBI", data[:8])
    payload = data[8:8 + size] if cipher == 0 else data[8:]
    if cipher == 2:
        if key is None:
            return None
        plain = aes(key, payload[:16], payload[16:], decrypt=True)
        payload = plain[:-plain[-1]]
    elif cipher != 0:
        return None
    comp, mtype = struct.unpack(">HH", payload[:4])
    cls = L.by_type.get((comp, mtype))
    if cls is None:
        return None
    msg = cls()
    msg.ParseFromString(payload[4:])
    return msg


class Robot:
    def __init__(self, conn):
        self.conn = conn
        self.rx = b""
        self.number = None
        self.beacons: list = []


class LeagueServer:
    """``port``: where robots connect (TCP); ``refbox``: (host, public send port,
    public recv port, team send port, team recv port) from this server's side;
    ``team``/``key``/``color`` (0 cyan, 1 magenta) as the refbox knows the team."""

    def __init__(self, port: int, refbox: tuple[str, int, int, int, int], team: str, key: str, color: int = 0):
        self.team, self.color = team, color
        self.key = hand_key(key, 16)
        self.lsock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.lsock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.lsock.bind(("127.0.0.1", port))
        self.lsock.listen(8)
        self.lsock.setblocking(False)
        self.port = self.lsock.getsockname()[1]
        host, pub_send, pub_recv, team_send, team_recv = refbox
        self.refbox_host, self.team_send = host, team_send

        def udp(port):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            s.bind(("0.0.0.0", port))
            s.setblocking(False)
            return s
        self.public = udp(pub_recv)
        self.team_sock = udp(team_recv)
        self.robots: list[Robot] = []
        self.results: dict[int, object] = {}        # task id -> the robot's echoed AgentTask
        self.game_state = None
        self.orders: dict[int, object] = {}
        self.machines: dict[str, object] = {}
        self.next_id = 100

    # -- the loop ----------------------------------------------------------------------------
    def poll(self) -> None:
        try:
            while True:
                conn, _ = self.lsock.accept()
                conn.setblocking(False)
                self.robots.append(Robot(conn))
        except BlockingIOError:
            pass
        for r in list(self.robots):
            self._read_robot(r)
        for sock, key in ((self.public, None), (self.team_sock, self.key)):
            while True:
                try:
                    data = sock.recv(65536)
                except BlockingIOError:
                    break
                msg = unframe(data, key)
                if msg is not None:
                    self._refbox(msg)

    def _read_robot(self, r: Robot) -> None:
        try:
            while True:
                data = r.conn.recv(65536)
                if not data:
                    self.robots.remove(r)
                    return
                r.rx += data
        except BlockingIOError:
            pass
        while len(r.rx) >= 8:
            size = struct.unpack(">I", r.rx[4:8])[0]
            if len(r.rx) < 8 + size:
                break
            data, r.rx = r.rx[:8 + size], r.rx[8 + size:]
            msg = unframe(data)
            name = msg.DESCRIPTOR.name if msg is not None else None
            if name == "BeaconSignal":
                r.number = msg.number
                r.beacons.append(msg)
            elif name == "AgentTask" and (msg.HasField("successful") or msg.HasField("canceled")):
                self.results[msg.task_id] = msg

    def _refbox(self, msg) -> None:
        name = msg.DESCRIPTOR.name
        if name == "GameState":
            self.game_state = msg
        elif name == "OrderInfo":
            for o in msg.orders:
                self.orders[o.id] = o
        elif name == "MachineInfo":
            for m in msg.machines:
                self.machines[m.name] = m

    # -- robots ------------------------------------------------------------------------------
    def robot(self, number: int) -> Robot | None:
        return next((r for r in self.robots if r.number == number), None)

    def task(self, robot: int, *, via: int | None = None, **body) -> int:
        """Send robot ``robot`` a task (``move={...}``, ``retrieve={...}`` ... as
        dicts, plus plain fields) over its link (``via``: over the link of that
        robot instead); returns its id."""
        self.next_id += 1
        t = L.AgentTask(team_color=self.color, task_id=self.next_id, robot_id=robot)
        for k, v in body.items():
            if isinstance(v, dict):
                getattr(t, k).SetInParent()
                for fk, fv in v.items():
                    setattr(getattr(t, k), fk, fv)
            else:
                setattr(t, k, v)
        self.send_robot(robot if via is None else via, t)
        return self.next_id

    def send_robot(self, robot: int, msg) -> None:
        r = self.robot(robot)
        assert r is not None, f"robot {robot} is not connected"
        r.conn.sendall(frame(msg))

    def result(self, task_id: int):
        return self.results.get(task_id)

    def error(self, task_id: int) -> str | None:
        res = self.results.get(task_id)
        return L.error_name.get(res.error_code) if res is not None and res.HasField("error_code") else None

    # -- refbox ------------------------------------------------------------------------------
    def prepare(self, machine: str, **instruction) -> None:
        """PrepareMachine: ``bs=(side, base)``, ``cs=op``, ``ds=order_id``, ``rs=ring``."""
        pm = L.PrepareMachine(team_color=self.color, machine=machine)
        if "bs" in instruction:
            pm.instruction_bs.side, pm.instruction_bs.color = instruction["bs"]
        if "cs" in instruction:
            pm.instruction_cs.operation = instruction["cs"]
        if "ds" in instruction:
            pm.instruction_ds.order_id = instruction["ds"]
        if "rs" in instruction:
            pm.instruction_rs.ring_color = instruction["rs"]
        self.team_sock.sendto(frame(pm, self.key), (self.refbox_host, self.team_send))

    def phase(self) -> tuple[int, float] | None:
        """(phase, game time) from the last GameState."""
        gs = self.game_state
        if gs is None:
            return None
        return gs.phase, gs.game_time.sec + gs.game_time.nsec * 1e-9

    def close(self) -> None:
        for r in self.robots:
            r.conn.close()
        for s in (self.lsock, self.public, self.team_sock):
            s.close()
