"""``rll-bt robotino emulate|probe|drive``: the emulator and bring-up tools."""
from __future__ import annotations

import argparse
import faulthandler
import json
import math
import signal
import sys

from rll_bt.backend import BackendError, BackendUnavailable
from rll_bt.clock import WallClock
from rll_bt.errors import Unavailable, UserError

from .rig import LASERS

CLOCK = WallClock()

EXIT_OK, EXIT_FAILURE = 0, 1


def _number(check, requirement: str):
    """An argparse type: a float that passes ``check``, else ``requirement`` is the error."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not (math.isfinite(value) and check(value)):
            raise argparse.ArgumentTypeError(f"{requirement}, got {text}")
        return value
    return parse


_probability = _number(lambda v: 0.0 <= v < 1.0, "probability must be in [0, 1)")
_non_negative = _number(lambda v: v >= 0, "must be a finite number >= 0")
_finite = _number(lambda v: True, "must be finite")


def register(cli) -> None:
    sub = cli.group("robotino")

    p = sub.add_parser("emulate", help="run a firmware-faithful Robotino 3 base on a pty",
                       description="Open a pty pair that behaves like the Robotino 3 base firmware "
                                   "(and with --gripper a second one like the RCLL gripper Arduino), "
                                   "print the device paths (stdout, one per line, base first) and "
                                   "serve until Ctrl-C or SIGTERM; a JSON summary line follows at exit.")
    p.add_argument("--gripper", action="store_true", help="also emulate the gripper Arduino")
    p.add_argument("--corrupt", type=_probability, default=0.0, metavar="P",
                   help="per-byte probability of corrupting a byte (both directions)")
    p.add_argument("--drop", type=_probability, default=0.0, metavar="P",
                   help="per-byte probability of dropping a byte (both directions)")
    p.add_argument("--delay", type=_non_negative, default=0.0, metavar="MS",
                   help="delay every byte sent to the host by MS milliseconds")
    p.add_argument("--close-every", type=_non_negative, default=0.0, metavar="S",
                   help="close (unplug) the ports every S seconds")
    p.add_argument("--closed-for", type=_non_negative, default=0.5, metavar="S",
                   help="how long a closed port stays away (default 0.5)")
    p.add_argument("--seed", type=int, default=None, metavar="N", help="seed of the fault RNG")
    p.add_argument("--link-dir", default=None, metavar="DIR",
                   help="directory for the device symlinks (default: a new temporary one)")
    p.add_argument("--firmware", default="1.2.3", metavar="VERSION",
                   help="firmware version to report (2.x drops the gyro; default 1.2.3)")
    p.add_argument("--laser", choices=LASERS, default=None,
                   help="also emulate a laser: urg (Hokuyo URG-04LX, SCIP 2.0 on a pty), urg-tcp "
                        "(Hokuyo UTM-30LX-EW, SCIP 2.0 on a TCP port) or tim (SICK TiM571, CoLa on a TCP port)")
    p.add_argument("--camera", action="store_true", help="also emulate the camera (MJPEG over HTTP on loopback)")
    p.add_argument("--config-out", default=None, metavar="FILE",
                   help="write the robot configuration of the emulated devices to FILE "
                        "(for rll-bt agent/robotino check --robot-config)")
    p.add_argument("--duration", type=_non_negative, default=0.0, metavar="S",
                   help="stop after S seconds (default: run until Ctrl-C)")
    p.add_argument("--report", type=_non_negative, default=5.0, metavar="S",
                   help="print a status line every S seconds (0: never; default 5)")
    p.set_defaults(func=_emulate)

    p = sub.add_parser("probe", help="connect to a base and print what it reports",
                       description="Connect to a Robotino 3 base, print versions, battery, bumper, "
                                   "motor readings and sensors.  Exit 3 if it cannot be reached.")
    p.add_argument("--device", default=None, help="base tty (default: find USB id 1E29:040D)")
    p.add_argument("--gripper-device", default=None, help="also query the gripper on this tty")
    p.add_argument("--timeout", type=_non_negative, default=1.0, metavar="S",
                   help="how long to wait for the base's version reply (default 1)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(func=_probe)

    p = sub.add_parser("drive", help="drive the base at a fixed velocity for a while",
                       description="Bring-up: drive at (vx, vy, omega) in the robot frame for "
                                   "SECONDS, printing odometry, then stop.")
    p.add_argument("--device", default=None, help="base tty (default: find USB id 1E29:040D)")
    p.add_argument("--vx", type=_finite, default=0.0, help="forward speed m/s (|vx| <= 1)")
    p.add_argument("--vy", type=_finite, default=0.0, help="leftward speed m/s (|vy| <= 1)")
    p.add_argument("--omega", type=_finite, default=0.0, help="turn rate rad/s (|omega| <= 3.5)")
    p.add_argument("--seconds", type=_finite, default=1.0, help="how long to drive (0 < S <= 120)")
    p.set_defaults(func=_drive)

    from .check import register as register_check
    register_check(sub)


# -- emulate ----------------------------------------------------------------------

def _serve(emu, args) -> None:
    """Serve for ``--duration`` seconds (0: until interrupted), a line of
    counts on stderr every ``--report`` seconds."""
    start = CLOCK.now()
    next_report = start + args.report if args.report > 0 else math.inf
    while args.duration <= 0 or CLOCK.now() - start < args.duration:
        CLOCK.sleep(0.05)
        if CLOCK.now() >= next_report:
            next_report += args.report
            s, pose = emu.stats(), emu.ground_truth()
            print(f"t={CLOCK.now() - start:6.1f}s frames={s['frames']} replies={s['replies']} "
                  f"checksum_errors={s['checksum_errors']} watchdog_trips={s['watchdog_trips']} "
                  f"pose=({pose[0]:.3f}, {pose[1]:.3f}, {pose[2]:.3f})", file=sys.stderr, flush=True)


def _emulate(args) -> int:
    from .emulator import RobotinoEmulator
    from .faults import Faults
    from .firmware import BaseFirmware

    try:
        faults = Faults(args.corrupt, args.drop, args.delay, args.close_every, args.closed_for, args.seed)
    except ValueError as exc:
        raise UserError(str(exc)) from None
    # SIGUSR1 prints every thread's stack to stderr: how to see where a hung emulator is
    faulthandler.register(signal.SIGUSR1, file=sys.__stderr__, all_threads=True)
    clock = CLOCK
    firmware = BaseFirmware(sw_version=args.firmware, start=clock.now())
    rig = None
    try:
        emu = RobotinoEmulator(gripper=args.gripper, faults=faults, link_dir=args.link_dir,
                               clock=clock, firmware=firmware)
        if args.laser or args.camera or args.config_out:
            from .rig import EmulatedRobot
            rig = EmulatedRobot(laser=args.laser, camera=args.camera, emulator=emu, link_dir=emu.link_dir,
                                clock=clock).start()
        else:
            emu.start()
    except OSError as exc:
        raise UserError(f"cannot create the emulator's ptys or sockets: {exc}", where=args.link_dir) from None
    if args.config_out:
        try:
            rig.write_config(args.config_out)
        except OSError as exc:
            rig.stop()
            raise UserError(f"cannot write the robot configuration: {exc}", where=args.config_out) from None
    # stop on SIGINT and SIGTERM alike, also when started in the background of a
    # non-interactive shell (which starts it with SIGINT ignored); installed before
    # the device paths go out, as whoever reads them may stop it at once
    def on_signal(signum, frame):
        raise KeyboardInterrupt
    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        # stdout: the device paths, one per line (base first), then the summary at exit;
        # stderr: what a person watching wants to read
        print(emu.device, flush=True)
        if emu.gripper_device:
            print(emu.gripper_device, flush=True)
        print(f"Robotino 3 base emulator (firmware {args.firmware}) running", file=sys.stderr)
        print(f"  base:    {emu.device}", file=sys.stderr)
        if emu.gripper_device:
            print(f"  gripper: {emu.gripper_device}", file=sys.stderr)
        if rig is not None and rig.laser_runner is not None:
            where = rig.laser_runner.link if args.laser == "urg" else "{}:{}".format(*rig.laser_runner.address)
            print(f"  laser:   {where} ({args.laser})", file=sys.stderr)
        if rig is not None and rig.camera_server is not None:
            print(f"  camera:  {rig.camera_server.url}", file=sys.stderr)
        if args.config_out:
            print(f"  config:  {args.config_out}", file=sys.stderr)
        print("press Ctrl-C to stop", file=sys.stderr, flush=True)
        _serve(emu, args)
    except KeyboardInterrupt:
        pass
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
        stats = emu.stats()
        if rig is not None:
            rig.stop()
        else:
            emu.stop()
    print("summary: " + json.dumps(stats, sort_keys=True), flush=True)
    return EXIT_OK


# -- probe ------------------------------------------------------------------------

def _open(device: str | None, **options):
    from .backend import RobotinoBackend
    try:
        return RobotinoBackend(device, **options)
    except BackendUnavailable as exc:
        raise Unavailable(str(exc)) from None


def _wait_for_readings(backend, timeout: float = 0.5) -> None:
    deadline = CLOCK.now() + timeout
    while CLOCK.now() < deadline:
        r = backend.readings()
        if r.power is not None and not math.isnan(r.stamp):
            return
        CLOCK.sleep(0.01)


def _probe(args) -> int:
    backend = _open(args.device, gripper_device=args.gripper_device,
                    handshake_timeout=max(args.timeout, 0.05))
    try:
        _wait_for_readings(backend)
        if args.gripper_device:
            CLOCK.sleep(0.3)
        report = _probe_report(backend)
    finally:
        backend.close()
    if args.json:
        print(json.dumps(report, sort_keys=True))
    else:
        _print_report(report)
    return EXIT_OK if report["battery"] is not None else EXIT_FAILURE


def _probe_report(backend) -> dict:
    r = backend.readings()
    try:
        b = backend.battery()
        battery = {"voltage": round(b.voltage, 3), "current": round(b.current, 3),
                   "soc": None if b.soc is None else round(b.soc, 3), "external_power": b.external_power}
    except BackendError:
        battery = None
    report = {
        "device": backend.base.device,
        "hardware_version": backend.versions[0], "firmware_version": backend.versions[1],
        "battery": battery, "bumper": r.bumper, "power_button": r.power_button,
        "motor_speeds_rpm": list(r.motor_speeds), "motor_positions_ticks": list(r.motor_positions),
        "motor_currents_a": [round(c, 3) for c in r.motor_currents],
        "distance_sensors_v": [round(v, 3) for v in r.distance_voltages],
        "analog_inputs_v": [round(v, 3) for v in r.analog_inputs],
        "digital_inputs": f"{r.digital_inputs:08b}",
        "link": dict(vars(backend.link_stats()).items()),
    }
    if backend.gripper is not None:
        g = backend.gripper_status()
        report["gripper"] = {"state": g.state.value, "open": g.is_open,
                             "position_m": [round(v, 5) for v in g.position], "message": g.message}
    return report


def _print_report(report: dict) -> None:
    print(f"Robotino base on {report['device']}")
    print(f"  hardware {report['hardware_version']}, firmware {report['firmware_version']}")
    b = report["battery"]
    if b:
        soc = "?" if b["soc"] is None else f"{100 * b['soc']:.0f} %"
        print(f"  battery  {b['voltage']:.2f} V, {b['current']:.2f} A, charge ~{soc}"
              f"{', external power' if b['external_power'] else ''}")
    else:
        print("  battery  no reading")
    print(f"  bumper   {'PRESSED' if report['bumper'] else 'free'}")
    print(f"  motors   speed {report['motor_speeds_rpm']} rpm, position {report['motor_positions_ticks']} "
          f"ticks, current {report['motor_currents_a']} A")
    print(f"  IR       {report['distance_sensors_v']} V")
    print(f"  analog   {report['analog_inputs_v']} V, digital {report['digital_inputs']}")
    link = report["link"]
    print(f"  link     {link['frames']} frames, {link['checksum_errors']} checksum errors, "
          f"{link['base_errors']} base errors")
    if "gripper" in report:
        g = report["gripper"]
        print(f"  gripper  {g['state']}, {'open' if g['open'] else 'closed'}, at {g['position_m']} m"
              f"{' ' + g['message'] if g['message'] else ''}")


# -- drive ------------------------------------------------------------------------

def _drive(args) -> int:
    if not 0 < args.seconds <= 120:
        raise UserError(f"--seconds must be in (0, 120], got {args.seconds:g}")
    for name, value, limit in (("--vx", args.vx, 1.0), ("--vy", args.vy, 1.0), ("--omega", args.omega, 3.5)):
        if abs(value) > limit:
            raise UserError(f"{name} {value:g} is beyond the bring-up limit of {limit:g}")
    backend = _open(args.device)
    try:
        start = CLOCK.now()
        next_print = start
        print(f"driving at vx={args.vx:g} m/s vy={args.vy:g} m/s omega={args.omega:g} rad/s "
              f"for {args.seconds:g} s", flush=True)
        while (t := CLOCK.now() - start) < args.seconds:
            backend.drive(args.vx, args.vy, args.omega)
            if CLOCK.now() >= next_print:
                next_print += 0.5
                _print_odometry(backend, t)
            CLOCK.sleep(0.02)
        backend.stop()
        CLOCK.sleep(0.5)
        _print_odometry(backend, CLOCK.now() - start, "stopped")
        stats = backend.link_stats()
    finally:
        backend.close()
    print(f"link: {stats.frames} frames, {stats.checksum_errors} checksum errors, "
          f"{stats.link_losses} link losses, {stats.reopens} reopens")
    return EXIT_OK if stats.link_losses == 0 else EXIT_FAILURE


def _print_odometry(backend, t: float, note: str = "") -> None:
    o = backend.odometry()
    print(f"t={t:5.2f}s x={o.pose.x:+.3f} m y={o.pose.y:+.3f} m theta={o.pose.theta:+.3f} rad "
          f"v=({o.vx:+.2f}, {o.vy:+.2f}, {o.omega:+.2f}) {note}".rstrip(), flush=True)


if __name__ == "__main__":  # pragma: no cover
    from rll_bt.cli import main
    sys.exit(main(["robotino", *sys.argv[1:]]))
