"""The world's stations as Festo PLCs on OPC-UA, one server per station.

What the refbox's OPC-UA back-end (``src/libs/mps_comm/opcua/`` of the
refbox, read, not copied) expects of an MPS PLC:

- an endpoint ``opc.tcp://<ip>:<port>/`` without security; the refbox's
  station config and the league's simulator give each station its own
  port, 4840 (C-BS) .. 4846 (C-SS) and 4850 (M-BS) .. 4856 (M-SS);
- two register blocks under ``Objects/2:DeviceSet/4:CPX-E-CEC-C1-PN/
  4:Resources/4:Application/3:GlobalVars/4:G`` (``device="codesys"``: the
  CODESYS soft-PLC's ``4:CODESYS Control Win V3/3:Resources/...``, which the
  refbox's ``plc_simulation`` mode looks for): ``4:In`` for the station's
  own commands (action id = type base 100..500 + operation) and ``4:Basic``
  for lights (21 red, 22 yellow, 23 green; 20 all off), set-type (10) and
  the heartbeat (0);
- in each block ``4:p`` with ``4:ActionId`` (UInt16), ``4:Data`` (UInt16
  with two children, ``Data[0]`` and ``Data[1]``, the payload words),
  ``4:BarCode`` (UInt32), ``4:Error`` (Byte), ``4:SlideCnt`` (UInt16) and the
  folder ``4:Status`` with Booleans ``Busy``, ``Ready``, ``Error``,
  ``Enable`` (and ``unused0``, ``unused1``, ``inSensor``, ``outSensor``);
- the handshake: the refbox writes ActionId, Data[0], Data[1], then
  ``Status/Enable`` (true for a command, false for the heartbeat it writes
  to Basic every second the queue is empty), then Error, 40 ms between
  commands; it subscribes to In's BarCode, Error, Status/Busy, Enable,
  Error, Ready and, on an RS, SlideCnt, and a step is done when Busy falls.

Here a write of ``Enable = true`` takes the command (the PLC accepts it and
clears Enable), a step sets In's Busy until it is done; the workpiece
sensor is In's ``Status/Ready``, the slide counter In's ``SlideCnt``.

Each read and write is answered ``response_delay`` s late (20 ms by
default).  The refbox's OPC-UA client (freeopcua's ``BinaryClient::Send``)
sends a request, then waits on a condition variable without a predicate for
the response its receive thread hands over; when the response arrives
before the sending thread has begun to wait (it was descheduled right
after sending, which on a loaded machine happens about once in a few
hundred requests to a server on the same host), the wake-up is lost, the
request "times out" after 10 s, and the refbox reconnects the station; a
ring or storage step caught by that broke the station.  Held 20 ms, the
answer comes after the wait has begun: against the real refbox 0 timeouts
in 3.5 min instead of 49 in 4 min (7 stations; ``benchmarks/refbox_machines.py
--wire opcua``).  A command costs the refbox five writes, so 100 ms more.
"""
from __future__ import annotations

import asyncio
import logging
import threading
from dataclasses import dataclass, field
from typing import Self

from .commands import CommandError, from_opcua
from .machine import Feedback

log = logging.getLogger(__name__)

#: port offsets as the refbox's default station config and the league's
#: simulator: cyan 4840 (C-BS) .. 4846 (C-SS), magenta 4850 (M-BS) .. 4856
PORT_ORDER = ("BS", "CS1", "CS2", "RS1", "RS2", "DS", "SS")
MAGENTA_OFFSET = 10
DEVICES = {"plc": ("CPX-E-CEC-C1-PN", 4), "codesys": ("CODESYS Control Win V3", 3)}
NAMESPACES = ("http://opcfoundation.org/UA/DI/",               # 2: DeviceSet
              "http://rll-bt/mps/GlobalVars",                   # 3: GlobalVars (codesys: Resources)
              "http://rll-bt/mps/IecVarAccess")                 # 4: the PLC's variables
STATUS_BITS = ("Busy", "Ready", "Error", "Enable", "unused0", "unused1", "inSensor", "outSensor")
#: s a read or write response is held back (0: answered at once); see the module doc
RESPONSE_DELAY = 0.02


def default_ports(machines, base: int = 4840) -> dict[str, int | None]:
    """Port per machine: ``base`` + its place in :data:`PORT_ORDER` (+10
    for magenta): C-BS 4840, C-SS 4846, M-BS 4850, M-SS 4856."""
    ports: dict[str, int | None] = {}
    for m in machines:
        team, _, kind = m.partition("-")
        ports[m] = (base + PORT_ORDER.index(kind) + (MAGENTA_OFFSET if team == "M" else 0)
                    if kind in PORT_ORDER and team in ("C", "M") else None)
    return ports


@dataclass
class _Block:
    """The nodes of one register block (In or Basic)."""
    action: object = None
    data: list = field(default_factory=list)
    barcode: object = None
    error: object = None
    slide: object = None
    status: dict = field(default_factory=dict)


class _Station:
    def __init__(self, machine: str, kind: str, port: int):
        self.machine, self.kind, self.port = machine, kind, port
        self.server = None
        self.blocks: dict[str, _Block] = {}
        self.enable_ids: dict = {}              # NodeId of Status/Enable -> block name


class OpcuaMachines:
    """Serve ``hall``'s machines as OPC-UA PLCs on ``host``.

    ``ports`` {machine: port} (default :func:`default_ports` from
    ``base_port``); ``device`` "plc" (the Festo CPX-E node names) or
    "codesys"; ``progress``: called with a line as each server comes up (each
    takes a second or more to build).  :meth:`start` returns once every server listens (raises
    ``OSError`` when a port is taken); :meth:`stop` ends them.  ``errors``
    lists refused register writes; ``received`` every command taken."""

    def __init__(self, hall, host: str = "127.0.0.1", *, ports: dict[str, int] | None = None,
                 base_port: int = 4840, device: str = "plc", progress=None,
                 response_delay: float = RESPONSE_DELAY):
        if device not in DEVICES:
            raise ValueError(f"unknown device {device!r} (known: {', '.join(DEVICES)})")
        self.hall, self.host, self.device = hall, host, device
        if not 0.0 <= response_delay <= 1.0:
            raise ValueError(f"response_delay must be 0..1 s, not {response_delay}")
        self.response_delay = float(response_delay)
        self._progress = progress                # called with a line per server started
        ports = dict(ports or default_ports(hall.machines, base_port))
        missing = [m for m in hall.machines if ports.get(m) is None]
        if missing:
            raise ValueError(f"no OPC-UA port for {', '.join(missing)}")
        self.stations = {m: _Station(m, hall[m].kind, int(ports[m])) for m in hall.machines}
        self.errors: list[str] = []
        self.received: list[tuple[str, object]] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._failure: BaseException | None = None
        self._stopping: asyncio.Event | None = None
        self._feedback: asyncio.Queue | None = None

    @property
    def ports(self) -> dict[str, int]:
        return {m: s.port for m, s in self.stations.items()}

    # -- life ------------------------------------------------------------------
    def start(self, timeout: float = 120.0) -> OpcuaMachines:
        self._thread = threading.Thread(target=self._run, name="mps-opcua", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise TimeoutError(f"OPC-UA servers not up within {timeout:.0f} s")
        if self._failure is not None:
            self._thread.join(10)
            raise self._failure
        self.hall.add_listener(self._on_feedback)
        return self

    def stop(self) -> None:
        try:
            self.hall.remove_listener(self._on_feedback)
        except ValueError:
            pass
        if self._loop is not None and self._stopping is not None and self._loop.is_running():
            self._loop.call_soon_threadsafe(self._stopping.set)
        if self._thread is not None:
            self._thread.join(15)

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    def _run(self) -> None:
        logging.getLogger("asyncua").setLevel(logging.ERROR)   # its no-security notices are expected here
        self._loop = asyncio.new_event_loop()
        try:
            self._loop.run_until_complete(self._serve())
        finally:
            self._loop.close()

    async def _serve(self) -> None:
        self._stopping = asyncio.Event()
        started = []
        try:
            for st in self.stations.values():
                await self._build(st)
                await st.server.start()
                started.append(st)
                if self._progress:
                    self._progress(f"OPC-UA {st.machine} on {self.host}:{st.port} "
                                   f"({len(started)}/{len(self.stations)})")
        except BaseException as e:
            self._failure = e if isinstance(e, OSError) else OSError(f"OPC-UA server: {e}")
            self._ready.set()
            for st in started:
                await st.server.stop()
            return
        self._feedback = asyncio.Queue()
        writer = asyncio.ensure_future(self._write_feedback())
        self._ready.set()
        await self._stopping.wait()
        writer.cancel()
        for st in started:
            await st.server.stop()

    # -- the address space -----------------------------------------------------------
    async def _build(self, st: _Station) -> None:
        from asyncua import Server, ua
        from asyncua.common.callback import CallbackType
        server = Server()
        await server.init()
        server.set_endpoint(f"opc.tcp://{self.host}:{st.port}/")
        server.set_server_name(f"rll-bt {st.machine}")
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        for i, uri in enumerate(NAMESPACES, start=2):
            idx = await server.register_namespace(uri)
            if idx != i:
                raise RuntimeError(f"namespace {uri} got index {idx}, the refbox needs {i}")
        device, resources_ns = DEVICES[self.device]
        node = await server.nodes.objects.add_object(ua.NodeId("DeviceSet", 2), "2:DeviceSet")
        node = await node.add_object(ua.NodeId(f"|var|{device}", 4), f"4:{device}")
        node = await node.add_object(ua.NodeId(f"|var|{device}.Resources", 4), f"{resources_ns}:Resources")
        node = await node.add_object(ua.NodeId(f"|var|{device}.Application", 4), "4:Application")
        node = await node.add_object(ua.NodeId(f"|appo|{device}.Application.GlobalVars", 3), "3:GlobalVars")
        g = await node.add_folder(ua.NodeId(f"|var|{device}.Application.G", 4), "4:G")
        for name in ("In", "Basic"):
            st.blocks[name] = await self._block(g, f"|var|{device}.Application.G.{name}", name, st)
        st.server = server

        async def on_write(event, dispatcher):
            await self._on_write(st, event)
            await self._hold(event)

        async def on_read(event, dispatcher):
            await self._hold(event)
        server.subscribe_server_callback(CallbackType.PostWrite, on_write)
        server.subscribe_server_callback(CallbackType.PostRead, on_read)

    async def _hold(self, event) -> None:
        """Hold a client's response ``response_delay`` s (see :data:`RESPONSE_DELAY`)."""
        if self.response_delay > 0 and getattr(event, "is_external", True):
            await asyncio.sleep(self.response_delay)

    async def _block(self, parent, path: str, name: str, st: _Station) -> _Block:
        from asyncua import ua
        block_node = await parent.add_object(ua.NodeId(path, 4), f"4:{name}")
        p = await block_node.add_folder(ua.NodeId(f"{path}.p", 4), "4:p")

        async def var(owner, label, value, vtype, writable=False):
            n = await owner.add_variable(ua.NodeId(f"{path}.p.{label}", 4), f"4:{label}",
                                         ua.Variant(value, vtype))
            if writable:
                await n.set_writable()
            return n

        b = _Block()
        b.action = await var(p, "ActionId", 0, ua.VariantType.UInt16, True)
        b.barcode = await var(p, "BarCode", 0, ua.VariantType.UInt32)
        data = await var(p, "Data", 0, ua.VariantType.UInt16, True)
        b.data = [await var(data, f"Data[{i}]", 0, ua.VariantType.UInt16, True) for i in (0, 1)]
        b.slide = await var(p, "SlideCnt", 0, ua.VariantType.UInt16)
        b.error = await var(p, "Error", 0, ua.VariantType.Byte, True)
        status = await p.add_folder(ua.NodeId(f"{path}.p.Status", 4), "4:Status")
        for bit in STATUS_BITS:
            b.status[bit] = await status.add_variable(ua.NodeId(f"{path}.p.Status.{bit}", 4), f"4:{bit}",
                                                      ua.Variant(False, ua.VariantType.Boolean))
            if bit == "Enable":
                await b.status[bit].set_writable()
        st.enable_ids[b.status["Enable"].nodeid] = name
        return b

    # -- the handshake -------------------------------------------------------------------
    async def _on_write(self, st: _Station, event) -> None:
        if not getattr(event, "is_external", True):
            return
        for wv in event.request_params.NodesToWrite:
            block = st.enable_ids.get(wv.NodeId)
            if block is None or wv.Value.Value is None or wv.Value.Value.Value is not True:
                continue
            b = st.blocks[block]
            action = int(await b.action.read_value())
            data = [int(await d.read_value()) for d in b.data]
            await self._set(b.status["Enable"], False, "Boolean")
            try:
                command = from_opcua(st.kind, action, *data)
            except CommandError as e:
                self.errors.append(f"{st.machine} {block}: {e}")
                log.warning("refused %s write: %s", st.machine, e)
                continue
            self.received.append((st.machine, command))
            self.hall.submit(st.machine, command)

    @staticmethod
    async def _set(node, value, vtype: str) -> None:
        from asyncua import ua
        await node.write_value(ua.DataValue(ua.Variant(value, getattr(ua.VariantType, vtype))))

    async def _write_feedback(self) -> None:
        """Write feedback to the registers in the order the machines gave it."""
        while True:
            node, value, vtype = await self._feedback.get()
            await self._set(node, value, vtype)

    def _on_feedback(self, fb: Feedback) -> None:
        st = self.stations.get(fb.machine)
        if st is None or self._loop is None:
            return
        b = st.blocks["In"]
        node = {"busy": b.status.get("Busy"), "ready": b.status.get("Ready"),
                "slide": b.slide, "barcode": b.barcode}.get(fb.what)
        if node is None:
            return
        if fb.what in ("busy", "ready"):
            item = (node, bool(fb.value), "Boolean")
        elif fb.what == "slide":
            item = (node, int(fb.value) & 0xFFFF, "UInt16")
        else:
            item = (node, int(fb.value) & 0xFFFFFFFF, "UInt32")
        self._loop.call_soon_threadsafe(self._feedback.put_nowait, item)


__all__ = ["DEVICES", "PORT_ORDER", "OpcuaMachines", "default_ports"]
