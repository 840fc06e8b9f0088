"""The world's stations on the refbox's MQTT machine topics.

``reference/refbox-mqtt.md``: the refbox publishes ``MPS/<NAME>/Command``
(QoS 2, plain ASCII); a station answers on ``MPS/<NAME>/Status``
(``BUSY``/``IDLE``), ``MPS/<NAME>/WP-Sensor`` (``WP``/``NoWP``),
``MPS/<NAME>/Barcode`` and, on a ring station, ``MPS/<NAME>/SlideCount``
(decimal integers), with no trailing newline.  The refbox handles Status,
WP-Sensor and SlideCount each on a new thread, so two messages published
back to back may reach its rules in the wrong order: feedback of one
station is spaced by ``gap`` seconds (30 ms by default).

One paho-mqtt client serves every machine of a :class:`MachineHall`.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from typing import Self

from .commands import CommandError, parse_mqtt
from .machine import Feedback

log = logging.getLogger(__name__)
PREFIX = "MPS"
QOS = 2


def feedback_message(fb: Feedback) -> tuple[str, str] | None:
    """(topic, payload) of a feedback, None for what MQTT does not carry."""
    if fb.what == "busy":
        return f"{PREFIX}/{fb.machine}/Status", "BUSY" if fb.value else "IDLE"
    if fb.what == "ready":
        return f"{PREFIX}/{fb.machine}/WP-Sensor", "WP" if fb.value else "NoWP"
    if fb.what == "barcode":
        return f"{PREFIX}/{fb.machine}/Barcode", str(int(fb.value))
    if fb.what == "slide":
        return f"{PREFIX}/{fb.machine}/SlideCount", str(int(fb.value))
    return None


class MqttMachines:
    """Serve ``hall``'s machines through the broker at ``host``:``port``.

    :meth:`start` connects (raises ``ConnectionError`` when the broker cannot
    be reached) and subscribes; :meth:`stop` disconnects.  ``errors`` lists
    the commands that were refused (unknown machine, bad payload)."""

    def __init__(self, hall, host: str = "127.0.0.1", port: int = 1883, *, gap: float = 0.03,
                 client_id: str = "rll-bt-stations"):
        import paho.mqtt.client as paho
        self.hall, self.host, self.port, self.gap = hall, host, int(port), float(gap)
        self.errors: list[str] = []
        self.received: list[tuple[str, str]] = []
        self._out: queue.SimpleQueue = queue.SimpleQueue()
        self._last: dict[str, float] = {}
        self._stop = threading.Event()
        self._subscribed = threading.Event()
        self._client = paho.Client(paho.CallbackAPIVersion.VERSION2, client_id=client_id,
                                   protocol=paho.MQTTv311, clean_session=True)
        self._client.on_connect = self._on_connect
        self._client.on_message = self._on_message
        self._client.on_subscribe = lambda *a, **k: self._subscribed.set()
        self._sender = threading.Thread(target=self._send_loop, name="mps-mqtt-out", daemon=True)

    # -- life -----------------------------------------------------------------
    def start(self, timeout: float = 10.0) -> MqttMachines:
        try:
            self._client.connect(self.host, self.port, keepalive=60)
        except OSError as e:
            raise ConnectionError(f"MQTT broker {self.host}:{self.port} unreachable: {e}") from None
        self._client.loop_start()
        if not self._subscribed.wait(timeout):
            self.stop()
            raise ConnectionError(f"MQTT broker {self.host}:{self.port}: no subscription "
                                  f"within {timeout:.0f} s")
        self.hall.add_listener(self._queue_feedback)
        self._sender.start()
        for m in self.hall:                       # what the sensors say now
            for what, value in m.state().items():
                if what in ("busy", "ready"):
                    self._queue_feedback(Feedback(m.name, what, value, m.world.time))
        return self

    def stop(self) -> None:
        self._stop.set()
        try:
            self.hall.remove_listener(self._queue_feedback)
        except ValueError:
            pass
        if self._sender.is_alive():
            self._sender.join(2.0)
        self._client.disconnect()
        self._client.loop_stop()

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- network thread --------------------------------------------------------
    def _on_connect(self, client, userdata, flags, reason, properties=None) -> None:
        if getattr(reason, "is_failure", False):
            log.error("MQTT connect refused: %s", reason)
            return
        client.subscribe(f"{PREFIX}/+/Command", qos=QOS)     # again after every reconnect

    def _on_message(self, client, userdata, msg) -> None:
        parts = msg.topic.split("/")
        if len(parts) != 3 or parts[0] != PREFIX or parts[2] != "Command":
            return
        machine = parts[1]
        payload = msg.payload.decode("ascii", errors="replace")
        self.received.append((machine, payload))
        if machine not in self.hall.machines:
            self._refuse(f"{machine}: not served here ({payload!r})")
            return
        try:
            command = parse_mqtt(msg.payload)
        except CommandError as e:
            self._refuse(f"{machine}: {e}")
            return
        self.hall.submit(machine, command)

    def _refuse(self, text: str) -> None:
        self.errors.append(text)
        log.warning("refused command %s", text)

    # -- feedback ---------------------------------------------------------------
    def _queue_feedback(self, fb: Feedback) -> None:
        msg = feedback_message(fb)
        if msg is not None:
            self._out.put((fb.machine, *msg))

    def _send_loop(self) -> None:
        while not self._stop.is_set():
            try:
                machine, topic, payload = self._out.get(timeout=0.1)
            except queue.Empty:
                continue
            wait = self._last.get(machine, 0.0) + self.gap - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            self._client.publish(topic, payload, qos=QOS, retain=False)
            self._last[machine] = time.monotonic()


__all__ = ["PREFIX", "MqttMachines", "feedback_message"]
