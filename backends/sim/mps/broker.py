"""Start an MQTT broker on loopback for the stations and a refbox.

Two brokers: ``amqtt`` (pure Python, shipped by the PyPI package of that
name, a dependency of the ``machines`` extra, so it is there wherever the
project is installed, no root needed) and ``mosquitto`` (Debian's, the
broker the refbox's MQTT back-end was written against; the Makefile
installs it as root).  ``kind="auto"`` takes mosquitto when it is on the
PATH, else amqtt.  Both run as a child process that :meth:`Broker.stop`
ends.
"""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from typing import Self


class BrokerError(RuntimeError):
    """The broker could not be started."""


def free_port(host: str = "127.0.0.1") -> int:
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def reachable(host: str, port: int, timeout: float = 0.2) -> bool:
    try:
        with socket.create_connection((host, port), timeout=timeout):
            return True
    except OSError:
        return False


class Broker:
    """A running broker: ``host``, ``port``, ``kind``; :meth:`stop` ends it.  It waits up
    to ``timeout`` s for the broker to listen (amqtt's start takes 15 s and more on a
    loaded 2-core machine; a broker that exits fails at once)."""

    def __init__(self, kind: str = "auto", host: str = "127.0.0.1", port: int | None = None,
                 timeout: float = 60.0):
        if kind == "auto":
            kind = "mosquitto" if shutil.which("mosquitto") else "amqtt"
        if kind not in ("amqtt", "mosquitto"):
            raise BrokerError(f"unknown broker {kind!r} (known: amqtt, mosquitto, auto)")
        self.kind, self.host = kind, host
        self.port = port or free_port(host)
        if reachable(host, self.port):
            raise BrokerError(f"{host}:{self.port} is already in use")
        self._dir = tempfile.TemporaryDirectory(prefix="rll-bt-broker-")
        self._log = open(os.path.join(self._dir.name, "broker.log"), "wb")  # noqa: SIM115 (closed by stop)
        self.proc = subprocess.Popen(self._command(), stdout=self._log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        while not reachable(host, self.port):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise BrokerError(f"{kind} did not start on {host}:{self.port} within {timeout:g} s: "
                                  f"{self.log()[-800:]}")
            time.sleep(0.05)

    def _command(self) -> list[str]:
        conf = os.path.join(self._dir.name, "broker.conf")
        if self.kind == "mosquitto":
            exe = shutil.which("mosquitto")
            if exe is None:
                raise BrokerError("mosquitto is not installed (apt-get install mosquitto, "
                                  "or use the amqtt broker)")
            with open(conf, "w") as f:
                f.write(f"listener {self.port} {self.host}\nallow_anonymous true\n"
                        "persistence false\n")
            return [exe, "-c", conf]
        with open(conf, "w") as f:
            f.write("listeners:\n  default:\n    type: tcp\n"
                    f"    bind: {self.host}:{self.port}\n"
                    "plugins:\n  amqtt.plugins.authentication.AnonymousAuthPlugin:\n"
                    "    allow_anonymous: true\n")
        script = ("import sys; from amqtt.scripts.broker_script import main; "
                  "sys.argv[0] = 'amqtt'; sys.exit(main())")
        return [sys.executable, "-c", script, "-c", conf]

    def log(self) -> str:
        try:
            self._log.flush()
            with open(os.path.join(self._dir.name, "broker.log"), "rb") as f:
                return f.read().decode(errors="replace")
        except (OSError, ValueError):
            return ""

    @property
    def url(self) -> str:
        return f"tcp://{self.host}:{self.port}"

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        self._log.close()
        self._dir.cleanup()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


__all__ = ["Broker", "BrokerError", "free_port", "reachable"]
