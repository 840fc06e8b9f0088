"""Shared pieces of the station-machine tests: a headless 2025 world whose
stations run as machines, stepped on a thread of its own at a speed-up, and
waiting helpers."""
from __future__ import annotations

import threading
import time

from backends.sim.mps import Durations, MachineHall

#: the Festo durations at a twentieth: a cap op takes 0.875 s, a belt move ~0.2 s
FAST = Durations().scaled(0.05)


class RunningWorld:
    """A world and its machine hall, stepped in ``dt`` steps as fast as
    ``rate`` (world seconds per wall second) allows, on a thread.  ``call``
    runs a function on the world's thread (the world is not thread-safe)."""

    def __init__(self, profile="rcll2025", seed=3, rate=4.0, dt=0.02, durations=FAST, **hall_options):
        from backends.sim import World
        self.world = World(profile, seed=seed)
        self.hall = MachineHall(self.world, durations=durations, **hall_options)
        self.rate, self.dt = rate, dt
        self._calls: list = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def start(self):
        self._thread.start()
        return self

    def _loop(self):
        t0 = time.monotonic()
        sim0 = self.world.time
        while not self._stop.is_set():
            with self._lock:
                calls, self._calls = self._calls, []
            for fn, box, done in calls:
                try:
                    box.append(("ok", fn()))
                except Exception as e:
                    box.append(("err", e))
                done.set()
            self.hall.update()
            ahead = (self.world.time - sim0) / self.rate - (time.monotonic() - t0)
            if ahead > 0:
                time.sleep(ahead)
            self.world.step(self.dt)

    def call(self, fn, timeout=10.0):
        box, done = [], threading.Event()
        with self._lock:
            self._calls.append((fn, box, done))
        assert done.wait(timeout), "the world thread did not answer"
        kind, value = box[0]
        if kind == "err":
            raise value
        return value

    def stop(self):
        self._stop.set()
        self._thread.join(5)
        self.world.close()


def wait_for(pred, timeout=15.0, what="condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = pred()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")
