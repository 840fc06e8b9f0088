"""The robot configuration file: which base, laser, camera and gripper a
Robotino has, where they are connected and where they sit on the robot.

    cfg = load_robot_config("robot.yaml")      # RobotConfig, or RobotConfigError

The file is YAML checked against ``robot_config.schema.json`` (beside this
module; editors can use it: ``# yaml-language-server: $schema=...``).
Lengths in metres, angles in degrees (radians in the objects made from it);
relative paths (the camera calibration) are taken from the file's folder.
Example::

    name: R1
    base: {type: robotino3, device: /dev/ttyACM0}
    laser:
      type: urg
      device: /dev/ttyACM1
      mount: {x: 0.12, y: 0.0, z: 0.2, yaw: 0}
    camera:
      source: /dev/video0
      calibration: front.yaml
      mount: {x: 0.2, z: 0.6, pitch: 20}
    gripper: {device: /dev/arduino, holding_sensor: "distance:8>1.5"}
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import yaml

from rll_bt.backend import CameraExtrinsics

SCHEMA_FILE = Path(__file__).with_name("robot_config.schema.json")


class RobotConfigError(ValueError):
    """A configuration file that cannot be used; the message names the file and the place."""


@dataclass(frozen=True)
class RobotConfig:
    path: Path | None
    name: str
    base: dict
    laser: dict | None
    camera: dict | None
    gripper: dict | None
    faults: dict

    # -- parts, as the drivers take them ----------------------------------------------
    def laser_mount(self):
        from backends.devices.laser import LaserMount
        m = (self.laser or {}).get("mount", {})
        return LaserMount(m.get("x", 0.0), m.get("y", 0.0), m.get("z", 0.2), math.radians(m.get("yaw", 0.0)),
                          bool(m.get("upside_down", False)))

    def camera_extrinsics(self) -> CameraExtrinsics:
        m = (self.camera or {}).get("mount", {})
        return CameraExtrinsics((m.get("x", 0.2), m.get("y", 0.0), m.get("z", 0.6)),
                                yaw=math.radians(m.get("yaw", 0.0)), pitch=math.radians(m.get("pitch", 0.0)))

    def resolve(self, name: str) -> str:
        """A path of the file, made absolute from the file's folder."""
        p = Path(name)
        if p.is_absolute() or self.path is None:
            return str(p)
        return str((self.path.parent / p).resolve())

    @property
    def stale(self) -> float:
        return float(self.faults.get("stale", 0.5))

    @property
    def camera_stale(self) -> float:
        return float(self.faults.get("camera_stale", max(2.0, self.stale)))

    @property
    def startup_wait(self) -> float:
        return float(self.faults.get("startup_wait", 5.0))


def schema() -> dict:
    return json.loads(SCHEMA_FILE.read_text())


def _where(error) -> str:
    return "/".join(str(p) for p in error.absolute_path) or "(top level)"


def parse_robot_config(data, path: Path | None = None) -> RobotConfig:
    import jsonschema
    where = str(path) if path is not None else "robot config"
    validator = jsonschema.Draft202012Validator(schema())
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        lines = [f"{_where(e)}: {e.message}" for e in errors[:8]]
        raise RobotConfigError(f"{where}: not a valid robot configuration:\n  " + "\n  ".join(lines))
    base = data["base"]
    if base["type"] == "robotino4" and "url" not in base:
        base = {**base, "url": "http://127.0.0.1"}
    return RobotConfig(path, data.get("name", "robotino"), base, data.get("laser"), data.get("camera"),
                       data.get("gripper"), data.get("faults", {}))


def load_robot_config(path: str | Path) -> RobotConfig:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise RobotConfigError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise RobotConfigError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f":{mark.line + 1}:{mark.column + 1}" if mark is not None else ""
        raise RobotConfigError(f"{path}{at}: not YAML: {getattr(exc, 'problem', exc)}") from None
    return parse_robot_config(data, path)


def as_config(value) -> RobotConfig:
    """A RobotConfig from itself, a path or a dict."""
    if isinstance(value, RobotConfig):
        return value
    if isinstance(value, dict):
        return parse_robot_config(value)
    return load_robot_config(value)
