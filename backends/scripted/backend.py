"""The scripted backend.

A script (a YAML file or a dict) gives, per reading, a timeline of values
keyed by the clock time in seconds since the backend was opened; a reading
returns the last entry at or before now::

    capabilities: [drive, odometry, gripper, bumper, battery]   # the default; laser, camera and
                                                                # detections it cannot script
    readings:
      holding:  [{t: 0, value: false}, {t: 2.5, value: true}]
      bumper:   [{t: 0, value: false}]
      battery:  [{t: 0, voltage: 24.1, soc: 0.9}]
      gripper:  [{t: 0, state: idle, is_open: true}]
      odometry: [{t: 0, x: 0, y: 0, theta: 0}]      # without it, drive commands are integrated
    faults:    # a method raises BackendError on its n-th call, or from time t
      - {method: gripper_close, call: 1, message: jammed}
      - {method: drive, after: 5.0, message: motor fault}

Every command is recorded in :attr:`ScriptedBackend.commands` as
``(t, method, args)``.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import yaml

from rll_bt.backend import (
    Backend,
    BackendError,
    Battery,
    Capability,
    GripperState,
    GripperStatus,
    Odometry,
    Pose2D,
    wrap_angle,
)
from rll_bt.clock import Clock, WallClock

_DEFAULT_CAPS = (Capability.DRIVE | Capability.ODOMETRY | Capability.GRIPPER | Capability.BUMPER
                 | Capability.BATTERY)
#: what a script can give readings for (a capability advertised must work: rll_bt.backend.check_backend)
_SCRIPTABLE = _DEFAULT_CAPS


def load_script(script: str | Path | dict | None) -> dict:
    """A script from a path or a dict (``None``: an empty script)."""
    if script is None:
        return {}
    if isinstance(script, dict):
        return script
    path = Path(script)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BackendError(f"scripted backend: script {path} not found") from None
    except yaml.YAMLError as exc:
        raise BackendError(f"scripted backend: {path} is not valid YAML: {exc}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise BackendError(f"scripted backend: {path} must be a mapping with readings/faults")
    return data


def _caps(names) -> Capability:
    if names is None:
        return _DEFAULT_CAPS
    caps = Capability.NONE
    for n in names:
        try:
            caps |= Capability[str(n).upper()]
        except KeyError:
            raise BackendError(f"scripted backend: unknown capability {n!r} "
                               f"(known: {', '.join(c.name.lower() for c in Capability if c.name != 'NONE')})"
                               ) from None
    names = [c for c in Capability if c.name != "NONE"]
    extra = [c.name.lower() for c in names if c in caps and c not in _SCRIPTABLE]
    if extra:
        scriptable = ", ".join(c.name.lower() for c in names if c in _SCRIPTABLE)
        raise BackendError(f"scripted backend: cannot script {' or '.join(extra)} readings (it scripts {scriptable})")
    return caps


class ScriptedBackend(Backend):
    """Replays scripted readings on ``clock`` and records every command."""

    name = "scripted"

    def __init__(self, script: str | Path | dict | None = None, clock: Clock | None = None, **overrides: Any):
        data = dict(load_script(script))
        data.update(overrides)
        self.clock = clock or WallClock()
        self.t0 = self.clock.now()
        self._caps = _caps(data.get("capabilities"))
        self.readings: dict[str, list[dict]] = {}
        for name, timeline in (data.get("readings") or {}).items():
            if not isinstance(timeline, list) or not all(isinstance(e, dict) for e in timeline):
                raise BackendError(f"scripted backend: readings.{name} must be a list of mappings with t")
            self.readings[name] = sorted(timeline, key=lambda e: float(e.get("t", 0.0)))
        self.faults = list(data.get("faults") or [])
        self.commands: list[tuple[float, str, tuple]] = []
        self._calls: dict[str, int] = {}
        self._vel = (0.0, 0.0, 0.0)
        self._pose = Pose2D()
        self._last_integrate = 0.0
        self._gripper_open = True
        self.closed = False

    # -- helpers ----------------------------------------------------------------
    def elapsed(self) -> float:
        """Seconds since the backend was opened (script time)."""
        return self.clock.now() - self.t0

    def _reading(self, name: str) -> dict | None:
        timeline = self.readings.get(name)
        if not timeline:
            return None
        now = self.elapsed()
        current = None
        for entry in timeline:
            if float(entry.get("t", 0.0)) <= now + 1e-9:
                current = entry
            else:
                break
        return current

    def _command(self, method: str, *args) -> None:
        n = self._calls[method] = self._calls.get(method, 0) + 1
        now = self.elapsed()
        for f in self.faults:
            if f.get("method") != method:
                continue
            if ("call" in f and int(f["call"]) == n) or ("after" in f and now >= float(f["after"])):
                self.commands.append((now, method + "!", args))
                raise BackendError(f"scripted fault in {method}: {f.get('message', 'fault')}")
        self.commands.append((now, method, args))

    def _require(self, cap: Capability, what: str) -> None:
        from rll_bt.backend import CapabilityError
        if not (self._caps & cap):
            raise CapabilityError(f"scripted: no {what}")

    def calls(self, method: str) -> list[tuple]:
        """The arguments of every recorded call of ``method``."""
        return [a for _, m, a in self.commands if m == method]

    # -- Backend ----------------------------------------------------------------
    @property
    def capabilities(self) -> Capability:
        return self._caps

    def _integrate(self) -> None:
        now = self.elapsed()
        dt = now - self._last_integrate
        self._last_integrate = now
        if dt <= 0:
            return
        vx, vy, w = self._vel
        p = self._pose
        c, s = math.cos(p.theta), math.sin(p.theta)
        self._pose = Pose2D(p.x + (c * vx - s * vy) * dt, p.y + (s * vx + c * vy) * dt, wrap_angle(p.theta + w * dt))

    def drive(self, vx: float, vy: float, omega: float) -> None:
        self._require(Capability.DRIVE, "drive")
        self._integrate()
        self._command("drive", vx, vy, omega)
        self._vel = (float(vx), float(vy), float(omega))

    def stop(self) -> None:
        self._integrate()
        self._command("stop")
        self._vel = (0.0, 0.0, 0.0)

    def odometry(self) -> Odometry:
        self._require(Capability.ODOMETRY, "odometry")
        r = self._reading("odometry")
        if r is not None:
            return Odometry(self.clock.now(), Pose2D(float(r.get("x", 0.0)), float(r.get("y", 0.0)),
                                                     float(r.get("theta", 0.0))),
                            float(r.get("vx", 0.0)), float(r.get("vy", 0.0)), float(r.get("omega", 0.0)))
        self._integrate()
        return Odometry(self.clock.now(), self._pose, *self._vel)

    def bumper(self) -> bool:
        self._require(Capability.BUMPER, "bumper")
        r = self._reading("bumper")
        return bool(r.get("value")) if r else False

    def battery(self) -> Battery:
        self._require(Capability.BATTERY, "battery")
        r = self._reading("battery") or {}
        return Battery(float(r.get("voltage", 24.0)), float(r.get("current", 0.0)), r.get("soc"),
                       bool(r.get("external_power", False)))

    def gripper_open(self) -> None:
        self._require(Capability.GRIPPER, "gripper")
        self._command("gripper_open")
        self._gripper_open = True

    def gripper_close(self) -> None:
        self._require(Capability.GRIPPER, "gripper")
        self._command("gripper_close")
        self._gripper_open = False

    def gripper_move(self, x: float, y: float, z: float) -> None:
        self._require(Capability.GRIPPER, "gripper")
        self._command("gripper_move", x, y, z)

    def gripper_status(self) -> GripperStatus:
        self._require(Capability.GRIPPER, "gripper")
        r = self._reading("gripper") or {}
        h = self._reading("holding")
        state = r.get("state", "idle")
        try:
            gs = GripperState(state)
        except ValueError:
            gs = GripperState.UNKNOWN
        return GripperStatus(gs, bool(r.get("is_open", self._gripper_open)),
                             tuple(r.get("position", (0.0, 0.0, 0.0))),
                             None if h is None else bool(h.get("value")), str(r.get("message", "")))

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.commands.append((self.elapsed(), "close", ()))
