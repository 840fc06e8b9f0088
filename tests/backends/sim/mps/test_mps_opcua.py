"""The world's stations as Festo PLCs over OPC-UA, an asyncua client acting
as the refbox's OPC-UA back-end: it finds the registers by the refbox's
browse paths, writes a command as the refbox does (ActionId, Data[0],
Data[1], Status/Enable, Error; the numbers written out here from the
refbox's register map, not produced by the code under test) and watches
In's Busy, Ready and SlideCnt through a subscription."""
from __future__ import annotations

import threading

import pytest
from asyncua import ua
from asyncua.sync import Client

from backends.sim.mps import OpcuaMachines
from backends.sim.mps.broker import free_port
from tests.support.mps_world import RunningWorld, wait_for

PLC_PATH = ["0:Objects", "2:DeviceSet", "4:CPX-E-CEC-C1-PN", "4:Resources", "4:Application",
            "3:GlobalVars", "4:G"]
MACHINES = ("C-BS", "C-CS1", "C-RS1", "C-DS", "C-SS")

#: one worker starts the module's servers once (each worker that ran one of these tests built its own)
pytestmark = pytest.mark.xdist_group("mps_opcua")


class FakeRefboxPlc:
    """One station's PLC as the refbox's OpcUaMachine sees it."""

    def __init__(self, port, path=PLC_PATH):
        self.client = Client(f"opc.tcp://127.0.0.1:{port}/")
        self.client.connect()
        root = self.client.nodes.root
        self.reg = {}
        for block in ("In", "Basic"):
            for name in ("ActionId", "Data", "Error", "BarCode", "SlideCnt"):
                self.reg[block, name] = root.get_child([*path, f"4:{block}", "4:p", f"4:{name}"])
            for bit in ("Busy", "Ready", "Enable"):
                self.reg[block, bit] = root.get_child([*path, f"4:{block}", "4:p", "4:Status", f"4:{bit}"])
        self.events: list[tuple[str, object]] = []
        self._lock = threading.Lock()
        names = {self.reg["In", n].nodeid: n for n in ("Busy", "Ready", "SlideCnt", "BarCode")}

        refbox = self

        class Handler:
            def datachange_notification(self, node, val, data):
                with refbox._lock:
                    refbox.events.append((names[node.nodeid], val))

        params = ua.CreateSubscriptionParameters(RequestedPublishingInterval=20, RequestedLifetimeCount=1000,
                                                 RequestedMaxKeepAliveCount=100, MaxNotificationsPerPublish=0,
                                                 Priority=0)
        self.sub = self.client.create_subscription(params, Handler())
        self.sub.subscribe_data_change([self.reg["In", n] for n in names.values()], queuesize=20)

    def write(self, block, action_id, d0=0, d1=0, enable=True):
        """The refbox's send_instruction: five writes, types from the nodes."""
        mark = len(self.events)
        self.reg[block, "ActionId"].write_value(ua.Variant(action_id, ua.VariantType.UInt16))
        data = self.reg[block, "Data"].get_children()
        data[0].write_value(ua.Variant(d0, ua.VariantType.UInt16))
        data[1].write_value(ua.Variant(d1, ua.VariantType.UInt16))
        self.reg[block, "Enable"].write_value(ua.Variant(enable, ua.VariantType.Boolean))
        self.reg[block, "Error"].write_value(ua.Variant(0, ua.VariantType.Byte))
        return mark

    def since(self, mark):
        with self._lock:
            return list(self.events[mark:])

    def step(self, action_id, d0=0, d1=0, *, ready=False, timeout=20.0):
        """Send an In command and wait until Busy has risen and fallen (and Ready, if asked)."""
        mark = self.write("In", action_id, d0, d1)
        wait_for(lambda: ("Busy", True) in self.since(mark), timeout, f"busy after {action_id}")
        wait_for(lambda: self.since(mark)[self.since(mark).index(("Busy", True)):].count(("Busy", False)),
                 timeout, f"idle after {action_id}")
        if ready:
            wait_for(lambda: ("Ready", True) in self.since(mark), timeout, f"ready after {action_id}")
        return self.since(mark)

    def close(self):
        self.sub.delete()
        self.client.disconnect()


@pytest.fixture(scope="module")
def rig():
    running = RunningWorld(rate=2.0, machines=MACHINES).start()
    ports = {m: free_port() for m in MACHINES}
    served = OpcuaMachines(running.hall, ports=ports).start(timeout=600.0)   # 55 s for 5 servers at load 40
    plcs = {m: FakeRefboxPlc(ports[m]) for m in MACHINES}
    yield running, served, plcs
    for plc in plcs.values():
        plc.close()
    served.stop()
    running.stop()


def at(running, machine, slot):
    return running.call(lambda: running.world.workpiece_at(machine, slot))


def put(running, machine, slot, base, rings=(), cap=None):
    return running.call(lambda: running.world.spawn_workpiece(machine, slot, base, rings, cap))


def take(running, machine, slot):
    return running.call(lambda: running.world.remove_workpiece(machine, slot))


def test_set_type_heartbeat_and_lights_go_to_the_basic_registers(rig):
    running, _served, plcs = rig
    plc = plcs["C-DS"]
    plc.write("Basic", 10, 4, 0)                 # identify: a delivery station (type 4)
    plc.write("Basic", 0, 0, 0, enable=False)    # the heartbeat
    plc.write("Basic", 21, 1)                    # red on
    plc.write("Basic", 22, 2)                    # yellow blink
    plc.write("Basic", 23, 0)                    # green off
    wait_for(lambda: running.call(lambda: running.world.lights("C-DS"))
             == {"RED": "ON", "YELLOW": "BLINK", "GREEN": "OFF"}, what="C-DS lights")
    assert running.hall["C-DS"].declared_type == "DS"
    assert plc.reg["Basic", "Enable"].read_value() is False       # the PLC took the command
    plc.write("Basic", 20)                       # all lights off
    wait_for(lambda: set(running.call(lambda: running.world.lights("C-DS")).values()) == {"OFF"},
             what="lights reset")


def test_base_station_over_opcua(rig):
    running, _, plcs = rig
    plc = plcs["C-BS"]
    plc.step(101, 3)                             # GET_BASE black (PLC colour code 3)
    seen = plc.step(102, 3, 1, ready=True)       # conveyor to the OUTPUT sensor (3), forward (1)
    assert ("Ready", True) in seen
    wp = at(running, "C-BS", "output")
    assert wp.base == "BASE_BLACK"
    mark = len(plc.events)
    take(running, "C-BS", "output")
    wait_for(lambda: ("Ready", False) in plc.since(mark), what="ready falls when taken")
    plc.write("In", 100)                         # reset


def test_cap_station_over_opcua(rig):
    running, _, plcs = rig
    plc = plcs["C-CS1"]
    put(running, "C-CS1", "input", "BASE_RED", cap="CAP_BLACK")
    plc.step(302, 2, 1)                          # to the middle
    plc.step(301, 1)                             # cap action: retrieve
    plc.step(302, 3, 1, ready=True)
    assert at(running, "C-CS1", "output").cap is None
    take(running, "C-CS1", "output")
    put(running, "C-CS1", "input", "BASE_SILVER")
    plc.step(302, 2, 1)
    plc.step(301, 2)                             # cap action: mount
    plc.step(302, 3, 1, ready=True)
    assert at(running, "C-CS1", "output").cap == "CAP_BLACK"
    take(running, "C-CS1", "output")


def test_ring_station_over_opcua(rig):
    running, _, plcs = rig
    plc = plcs["C-RS1"]
    mark = len(plc.events)
    put(running, "C-RS1", "slide", "BASE_RED")
    wait_for(lambda: ("SlideCnt", 1) in plc.since(mark), what="slide counter 1")
    put(running, "C-RS1", "input", "BASE_RED")
    plc.step(202, 2, 1)
    plc.step(203, 2, 2)                          # feeder 2, ring colour enum 2 (green)
    plc.step(202, 3, 1, ready=True)
    assert at(running, "C-RS1", "output").rings == ("RING_GREEN",)
    take(running, "C-RS1", "output")


def test_delivery_and_storage_over_opcua(rig):
    running, _, plcs = rig
    wp = put(running, "C-DS", "input", "BASE_RED", cap="CAP_GREY")
    plcs["C-DS"].step(401, 3)                    # deliver, slot 3
    assert at(running, "C-DS", "input") is None
    assert running.hall["C-DS"].delivered[-1].data == {"workpiece": wp, "slot": 3}
    ss = plcs["C-SS"]
    ss.step(530, 5, 1)                           # retrieve shelf 5 slot 1: BASE_BLACK CAP_BLACK
    ss.step(502, 3, 1, ready=True)
    out = at(running, "C-SS", "output")
    assert (out.base, out.cap) == ("BASE_BLACK", "CAP_BLACK")
    take(running, "C-SS", "output")
    ss.step(550, 41, 43)                         # relocate shelf 4 slot 1 -> shelf 4 slot 3
    assert (4, 3) in running.hall["C-SS"].storage and (4, 1) not in running.hall["C-SS"].storage


def test_answers_are_held_so_the_refbox_client_is_waiting_for_them(rig):
    # freeopcua's client loses an answer that arrives before it waits for it (a lost wake-up,
    # then "Response timed out" and a reconnect): every read and write answer is held 20 ms
    import time
    _running, served, plcs = rig
    assert served.response_delay == pytest.approx(0.02)
    node = plcs["C-BS"].reg["Basic", "Error"]
    for op in (lambda: node.write_value(ua.Variant(0, ua.VariantType.Byte)), node.read_value):
        t0 = time.monotonic()
        op()
        assert time.monotonic() - t0 >= 0.02


def test_a_write_that_is_no_command_is_refused(rig):
    _running, served, plcs = rig
    n = len(served.errors)
    plcs["C-BS"].write("In", 399)                # a cap-station id on the base station
    wait_for(lambda: len(served.errors) > n, what="refusal")
    assert "C-BS" in served.errors[-1]


def test_the_codesys_node_names_of_the_refbox_plc_simulation_mode():
    running = RunningWorld(rate=2.0, machines=("C-DS",)).start()
    port = free_port()
    served = OpcuaMachines(running.hall, ports={"C-DS": port}, device="codesys").start()
    try:
        path = ["0:Objects", "2:DeviceSet", "4:CODESYS Control Win V3", "3:Resources", "4:Application",
                "3:GlobalVars", "4:G"]
        plc = FakeRefboxPlc(port, path)
        try:
            plc.write("Basic", 23, 2)                  # green blink
            wait_for(lambda: running.call(lambda: running.world.lights("C-DS"))["GREEN"] == "BLINK",
                     what="green blink")
        finally:
            plc.close()
    finally:
        served.stop()
        running.stop()
