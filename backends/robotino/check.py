"""``rll-bt robotino check --robot-config FILE``: bring up every device of
a robot configuration, one after the other, and say for each whether it was
found, how fast it delivers and what it delivered first.

Exit codes: 0 every device found and delivering, 2 a bad configuration
file, 3 at least one device missing or silent (each named with why).
"""
from __future__ import annotations

import json
import math
import sys

from rll_bt.clock import WallClock
from rll_bt.errors import UserError

CLOCK = WallClock()
EXIT_OK, EXIT_UNREACHABLE = 0, 3


def register(sub) -> None:
    p = sub.add_parser("check", help="bring up every device of a robot configuration and report each",
                       description=__doc__.split("\n\n")[0].replace("\n", " ").split(": ", 1)[1],
                       epilog="exit codes: 0 all found, 2 bad configuration, 3 a device missing or silent")
    p.add_argument("--robot-config", required=True, metavar="FILE", help="the robot configuration (YAML)")
    p.add_argument("--seconds", type=float, default=1.0, metavar="S",
                   help="how long to measure each device's rate (default 1)")
    p.add_argument("--timeout", type=float, default=3.0, metavar="S",
                   help="how long to wait for each device's first reading (default 3)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(func=_check)


def _measure(count, seconds: float) -> float:
    start, n0 = CLOCK.now(), count()
    CLOCK.sleep(seconds)
    return (count() - n0) / max(CLOCK.now() - start, 1e-9)


def _wait(ready, timeout: float) -> bool:
    end = CLOCK.now() + timeout
    while CLOCK.now() < end:
        if ready():
            return True
        CLOCK.sleep(0.02)
    return ready()


def check_base(cfg, args) -> dict:
    if cfg.base["type"] == "robotino4":
        from backends.robotino_rest.client import RestClient, RestError
        url = cfg.base.get("url", "http://127.0.0.1")
        try:
            odo = RestClient(url, timeout=args.timeout).get_json("/data/odometry")
        except RestError as exc:
            return {"found": False, "where": url, "why": f"REST API not reachable: {exc}"}
        return {"found": True, "where": url, "first": f"odometry {odo}"}
    from rll_bt.backend import BackendError

    from .base import RobotinoBase
    base = RobotinoBase(cfg.base.get("device"), clock=CLOCK, handshake_timeout=args.timeout)
    try:
        base.open()
    except BackendError as exc:
        return {"found": False, "where": base.device or "USB 1E29:040D", "why": str(exc)}
    try:
        rate = _measure(lambda: base.stats().frames, args.seconds)
        r = base.readings()
        power = f"{r.power.voltage:.2f} V" if r.power is not None else "no power reading"
        hw, sw = base.versions
        return {"found": True, "where": base.device, "rate_hz": round(rate, 1),
                "first": f"hardware {hw}, firmware {sw}, battery {power}, bumper {'pressed' if r.bumper else 'free'}"}
    finally:
        base.close()


def check_laser(cfg, args) -> dict:
    from .parts import make_laser
    laser = make_laser(cfg, CLOCK)
    where = laser.describe()
    laser.start()
    try:
        if not _wait(lambda: laser.latest() is not None, args.timeout):
            return {"found": False, "where": where,
                    "why": f"no scan within {args.timeout:g} s ({laser.stats().last_error or 'no reply'})"}
        rate = _measure(lambda: laser.stats().scans, args.seconds)
        s = laser.latest()
        finite = s.ranges[s.ranges < math.inf]
        front = s.ranges[len(s.ranges) // 2]
        model = laser.info.get("PROD") or laser.info.get("DeviceIdent") or laser.kind
        span = math.degrees(s.angle_increment * (len(s.ranges) - 1))
        first = f"{model}: {len(s.ranges)} beams over {span:.0f} deg, "
        first += (f"{len(finite)} with an echo ({finite.min():.2f}..{finite.max():.2f} m), ahead {front:.2f} m"
                  if len(finite) else "no echo")
        return {"found": True, "where": where, "rate_hz": round(rate, 1), "first": first}
    finally:
        laser.close()


def check_camera(cfg, args) -> dict:
    from .parts import make_camera
    cam = make_camera(cfg, CLOCK)
    cam.start()
    try:
        if not _wait(lambda: cam.latest() is not None, args.timeout + 2.0):
            return {"found": False, "where": str(cam.source),
                    "why": f"no frame within {args.timeout + 2.0:g} s ({cam.stats().last_error or 'nothing arrived'})"}
        rate = _measure(lambda: cam.stats().frames, args.seconds)
        f = cam.latest()
        h, w = f.image.shape[:2]
        return {"found": True, "where": str(cam.source), "rate_hz": round(rate, 1),
                "first": f"{w}x{h} frame, fx {f.intrinsics.fx:.1f} px, mean grey {float(f.image.mean()):.0f}"}
    finally:
        cam.close()


def check_gripper(cfg, args) -> dict:
    from rll_bt.backend import BackendError, GripperState

    from .gripper import ArduinoGripper
    device = cfg.gripper["device"]
    try:
        g = ArduinoGripper(device, clock=CLOCK).open()
    except BackendError as exc:
        return {"found": False, "where": device, "why": str(exc)}
    try:
        if not _wait(lambda: g.stats.lines > 0, args.timeout):
            return {"found": False, "where": device, "why": f"no valid line within {args.timeout:g} s"}
        st = g.status()
        return {"found": st.state is not GripperState.UNKNOWN or g.stats.hellos > 0, "where": device,
                "first": f"{st.state.value}, {'open' if st.is_open else 'closed'}, {g.stats.lines} lines, "
                         f"{g.stats.rejected} rejected"}
    finally:
        g.close()


def _check(args) -> int:
    from .config import RobotConfigError, load_robot_config
    try:
        cfg = load_robot_config(args.robot_config)
    except RobotConfigError as exc:
        raise UserError(str(exc), hint="the schema is backends/robotino/robot_config.schema.json") from None
    report = {}
    steps = [("base", check_base, True), ("laser", check_laser, cfg.laser),
             ("camera", check_camera, cfg.camera), ("gripper", check_gripper, cfg.gripper)]
    for name, fn, wanted in steps:
        if not wanted:
            report[name] = {"found": None, "why": "not configured"}
            continue
        if not args.json:
            print(f"checking {name} ...", file=sys.stderr, flush=True)
        try:
            report[name] = fn(cfg, args)
        except Exception as exc:          # a device that breaks while being checked is a finding, not a crash
            report[name] = {"found": False, "why": f"{type(exc).__name__}: {exc}"}
    missing = [n for n, r in report.items() if r["found"] is False]
    if args.json:
        print(json.dumps({"config": str(args.robot_config), "devices": report, "missing": missing}, sort_keys=True))
    else:
        print(f"robot configuration {args.robot_config} ({cfg.name})")
        for name, r in report.items():
            if r["found"] is None:
                print(f"  {name:8s} -        not configured")
            elif r["found"]:
                rate = f"{r['rate_hz']:6.1f} Hz" if "rate_hz" in r else "        "
                print(f"  {name:8s} found    {rate}  {r.get('where', '')}: {r.get('first', '')}")
            else:
                print(f"  {name:8s} MISSING            {r.get('where', '')}: {r['why']}")
        print("all configured devices found" if not missing else f"missing: {', '.join(missing)}")
    return EXIT_OK if not missing else EXIT_UNREACHABLE
