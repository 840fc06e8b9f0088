"""The world's stations over MQTT through a real broker, the test acting as
the refbox: it publishes the refbox's command payloads
(``reference/refbox-mqtt.md`` section 3, written out here, not produced by
the code under test) and reads the feedback topics."""
from __future__ import annotations

import threading

import paho.mqtt.client as paho
import pytest

from backends.sim.mps import Broker, MqttMachines
from tests.support.mps_world import RunningWorld, wait_for

#: s a step may take on a loaded machine (a step is ~1 world s; the world runs at 4x when it can)
STEP_TIMEOUT = 60.0

#: one worker starts the module's servers once (each worker that ran one of these tests built its own)
pytestmark = pytest.mark.xdist_group("mps_mqtt")


class FakeRefbox:
    """An MQTT client that publishes commands and records feedback, as the
    refbox's per-station clients do (QoS 2, MQTT 3.1.1)."""

    def __init__(self, host, port, running):
        self.running = running                              # the world, for the station's own state
        self.msgs: list[tuple[str, str, str]] = []        # (machine, topic leaf, payload)
        self._lock = threading.Lock()
        self.c = paho.Client(paho.CallbackAPIVersion.VERSION2, client_id="Refbox_test",
                             protocol=paho.MQTTv311)
        subscribed = threading.Event()
        self.c.on_message = self._on_message
        self.c.on_subscribe = lambda *a, **k: subscribed.set()
        self.c.connect(host, port)
        self.c.loop_start()
        self.c.subscribe([("MPS/+/Status", 2), ("MPS/+/WP-Sensor", 2), ("MPS/+/SlideCount", 2),
                          ("MPS/+/Barcode", 2)])
        assert subscribed.wait(60)

    def _on_message(self, client, userdata, msg):
        _, machine, leaf = msg.topic.split("/")
        with self._lock:
            self.msgs.append((machine, leaf, msg.payload.decode()))

    def send(self, machine, payload):
        mark = len(self.msgs)
        self.c.publish(f"MPS/{machine}/Command", payload, qos=2).wait_for_publish(5)
        return mark

    def since(self, mark, machine):
        with self._lock:
            return [(leaf, p) for m, leaf, p in self.msgs[mark:] if m == machine]

    def wait(self, mark, machine, leaf, payload, timeout=STEP_TIMEOUT):
        return wait_for(lambda: (leaf, payload) in self.since(mark, machine), timeout,
                        f"{machine} {leaf} {payload}")

    def step(self, machine, payload, *, wp=False):
        """Send a step command and return the feedback seen since: the step is over when
        the world's station has taken the command and is idle again (its own truth, read on
        the world's thread), and its BUSY and the IDLE it sent after have both arrived
        (and WP, with ``wp``).  Neither a stale IDLE (a duplicate, a reconnect) nor an
        IDLE that overtook its BUSY in the broker can end the step early or hang it."""
        station = self.running.hall[machine]
        taken = self.running.call(lambda: len(station.records))
        mark = self.send(machine, payload)
        wait_for(lambda: self.running.call(lambda: not station.busy and any(
            r.text.startswith(f"command {payload.split()[0]}") for r in station.records[taken:])),
            STEP_TIMEOUT, f"{machine} done with {payload}")
        self.wait(mark, machine, "Status", "BUSY")
        self.wait(mark, machine, "Status", "IDLE")
        if wp:
            self.wait(mark, machine, "WP-Sensor", "WP")
        return self.since(mark, machine)

    def close(self):
        self.c.loop_stop()
        self.c.disconnect()


@pytest.fixture(scope="module")
def rig():
    broker = Broker("amqtt")
    running = RunningWorld().start()
    served = MqttMachines(running.hall, broker.host, broker.port).start(timeout=60.0)
    refbox = FakeRefbox(broker.host, broker.port, running)
    yield running, served, refbox
    refbox.close()
    served.stop()
    running.stop()
    broker.stop()


def at(running, machine, slot):
    return running.call(lambda: running.world.workpiece_at(machine, slot))


def put(running, machine, slot, base, rings=(), cap=None):
    """A robot puts a workpiece at a slot."""
    return running.call(lambda: running.world.spawn_workpiece(machine, slot, base, rings, cap))


def take(running, machine, slot):
    return running.call(lambda: running.world.remove_workpiece(machine, slot))


def test_lights_follow_the_three_light_commands(rig):
    running, _, refbox = rig
    for payload in ("LIGHT RED ON", "LIGHT YELLOW BLINK", "LIGHT GREEN OFF"):
        refbox.send("C-CS2", payload)
    wait_for(lambda: running.call(lambda: running.world.lights("C-CS2"))
             == {"RED": "ON", "YELLOW": "BLINK", "GREEN": "OFF"}, STEP_TIMEOUT, "C-CS2 lights")
    refbox.send("M-DS", "LIGHT GREEN ON")
    wait_for(lambda: running.call(lambda: running.world.lights("M-DS"))["GREEN"] == "ON",
             STEP_TIMEOUT, "M-DS green")


def test_base_station_dispenses_and_the_belt_brings_the_base_out(rig):
    running, _, refbox = rig
    seen = refbox.step("C-BS", "GET_BASE RED")
    assert ("Status", "BUSY") in seen
    assert at(running, "C-BS", "output") is None
    seen = refbox.step("C-BS", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    last_idle = len(seen) - 1 - seen[::-1].index(("Status", "IDLE"))
    assert seen.index(("WP-Sensor", "WP")) < last_idle          # the refbox hears WP before IDLE
    wp = at(running, "C-BS", "output")
    assert wp is not None and wp.base == "BASE_RED" and wp.rings == () and wp.cap is None
    mark = len(refbox.msgs)
    take(running, "C-BS", "output")                          # the robot takes the base
    refbox.wait(mark, "C-BS", "WP-Sensor", "NoWP")
    refbox.send("C-BS", "RESET")
    # the other side: a base to the input
    refbox.step("C-BS", "GET_BASE SILVER")
    refbox.step("C-BS", "MOVE_CONVEYOR TO_INPUT IN", wp=True)
    assert at(running, "C-BS", "input").base == "BASE_SILVER"
    take(running, "C-BS", "input")


def test_cap_station_buffers_then_mounts_a_cap(rig):
    running, _, refbox = rig
    put(running, "C-CS1", "input", "BASE_BLACK", cap="CAP_GREY")        # a cap carrier from the shelf
    refbox.step("C-CS1", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.step("C-CS1", "CAP_ACTION RETRIEVE")
    assert running.hall["C-CS1"].cap_buffer == "CAP_GREY"
    refbox.step("C-CS1", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    carrier = at(running, "C-CS1", "output")
    assert carrier.cap is None and carrier.base == "BASE_BLACK"
    mark = len(refbox.msgs)
    take(running, "C-CS1", "output")
    refbox.wait(mark, "C-CS1", "WP-Sensor", "NoWP")
    refbox.send("C-CS1", "RESET")

    put(running, "C-CS1", "input", "BASE_RED", rings=("RING_BLUE",))
    refbox.step("C-CS1", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.step("C-CS1", "CAP_ACTION MOUNT")
    refbox.step("C-CS1", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    product = at(running, "C-CS1", "output")
    assert (product.base, product.rings, product.cap) == ("BASE_RED", ("RING_BLUE",), "CAP_GREY")
    assert running.hall["C-CS1"].cap_buffer is None
    take(running, "C-CS1", "output")


def test_ring_station_counts_slide_bases_and_mounts_the_feeders_ring(rig):
    running, _, refbox = rig
    mark = len(refbox.msgs)
    put(running, "C-RS1", "slide", "BASE_RED")
    refbox.wait(mark, "C-RS1", "SlideCount", "1")
    put(running, "C-RS1", "slide", "BASE_BLACK")
    refbox.wait(mark, "C-RS1", "SlideCount", "2")
    assert running.call(lambda: running.world.workpieces_at("C-RS1", "slide")) == ()
    put(running, "C-RS1", "input", "BASE_SILVER")
    refbox.step("C-RS1", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.step("C-RS1", "MOUNT_RING RING1")          # 2025: C-RS1 feeders orange, green
    refbox.step("C-RS1", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    assert at(running, "C-RS1", "output").rings == ("RING_ORANGE",)
    take(running, "C-RS1", "output")
    put(running, "M-RS2", "input", "BASE_RED", rings=("RING_GREEN",))
    refbox.step("M-RS2", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.step("M-RS2", "MOUNT_RING RING2")          # M-RS2: blue, yellow
    refbox.step("M-RS2", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    assert at(running, "M-RS2", "output").rings == ("RING_GREEN", "RING_YELLOW")
    take(running, "M-RS2", "output")


def test_delivery_station_takes_the_product_into_the_slot(rig):
    running, _, refbox = rig
    wp = put(running, "C-DS", "input", "BASE_BLACK", rings=("RING_GREEN",), cap="CAP_BLACK")
    seen = refbox.step("C-DS", "DELIVER SLOT2")
    assert ("Status", "BUSY") in seen
    assert at(running, "C-DS", "input") is None
    delivered = running.hall["C-DS"].delivered[-1]
    assert delivered.data["slot"] == 2 and delivered.data["workpiece"].id == wp.id


def test_storage_station_retrieves_and_stores(rig):
    running, _, refbox = rig
    refbox.step("C-SS", "RETRIEVE 0,1")               # pre-filled: BASE_RED CAP_GREY
    refbox.step("C-SS", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    wp = at(running, "C-SS", "output")
    assert (wp.base, wp.cap) == ("BASE_RED", "CAP_GREY")
    take(running, "C-SS", "output")
    refbox.send("C-SS", "RESET")
    put(running, "C-SS", "input", "BASE_SILVER", cap="CAP_BLACK")
    refbox.step("C-SS", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.step("C-SS", "STORE 2,3")
    assert at(running, "C-SS", "input") is None
    assert running.hall["C-SS"].storage[(2, 3)].base == "BASE_SILVER"
    refbox.step("C-SS", "RELOCATE 2,3 4,4")
    assert (4, 4) in running.hall["C-SS"].storage and (2, 3) not in running.hall["C-SS"].storage


def test_bad_commands_are_refused_and_the_station_keeps_working(rig):
    running, served, refbox = rig
    n = len(served.errors)
    refbox.send("C-BS", "LIGHT PINK ON")
    refbox.send("C-BS", "EXPLODE")
    refbox.send("C-XX", "RESET")
    wait_for(lambda: len(served.errors) >= n + 3, STEP_TIMEOUT, "three refusals")
    assert any("PINK" in e for e in served.errors[n:])
    refbox.step("C-BS", "GET_BASE BLACK")
    refbox.step("C-BS", "MOVE_CONVEYOR TO_OUTPUT OUT", wp=True)
    assert at(running, "C-BS", "output").base == "BASE_BLACK"
    take(running, "C-BS", "output")


def test_conveyor_waits_for_the_robots_workpiece(rig):
    running, _, refbox = rig
    mark = refbox.send("C-CS2", "MOVE_CONVEYOR TO_OUTPUT MID")
    refbox.wait(mark, "C-CS2", "Status", "BUSY")
    running.call(lambda: running.world.step(1.0))
    # not IDLE again after its BUSY (an IDLE the station published just before it took the command
    # can arrive after the mark: the station's periodic status)
    def after_busy():
        seen = refbox.since(mark, "C-CS2")
        return seen[seen.index(("Status", "BUSY")) + 1:]
    assert ("Status", "IDLE") not in after_busy(), refbox.since(mark, "C-CS2")
    put(running, "C-CS2", "input", "BASE_RED", cap="CAP_BLACK")     # the robot arrives
    wait_for(lambda: ("Status", "IDLE") in after_busy(), STEP_TIMEOUT, "C-CS2 IDLE after its BUSY")
    refbox.send("C-CS2", "RESET")                      # the referee clears the belt
    wait_for(lambda: at(running, "C-CS2", "input") is None, STEP_TIMEOUT, "belt cleared")
