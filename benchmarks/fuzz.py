"""Many inputs into every decoder; counts the inputs that escape as an unexpected exception.

    python benchmarks/fuzz.py                     # 100 000 inputs a decoder
    python benchmarks/fuzz.py -n 2000 --only urg  # a quick look at one

Each target takes bytes (or text) from outside: refbox frames (2016 and
2025 sets, plain and encrypted), team-server frames (the message set and
the secured link), the Robotino's serial frames and tags, the gripper's
lines, laser telegrams (URG SCIP 2.0, SICK CoLa-A and CoLa-B), YAML trees
and the robot configuration.  Inputs are mutations of valid ones (bit
flips, bytes set, cut, inserted, repeated, spliced) and plain random bytes,
from a seed.  A decoder may reject an input with the error it documents;
anything else (a ``KeyError``, an ``IndexError``, a recursion error...)
is an *escape*, printed with its input.  The suite keeps smaller
hypothesis runs of the same decoders; this is the long run.
"""
from __future__ import annotations

import argparse
import random
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Target:
    name: str
    seeds: list[bytes]
    run: Callable[[bytes], object]
    allowed: tuple[type[BaseException], ...] = ()
    note: str = ""
    escapes: list[tuple[bytes, str]] = field(default_factory=list)
    rejected: int = 0


# -- mutation ---------------------------------------------------------------------------
def mutate(rng: random.Random, seeds: list[bytes]) -> bytes:
    if rng.random() < 0.08:
        return rng.randbytes(rng.randint(0, 300))
    data = bytearray(rng.choice(seeds))
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(7)
        n = len(data)
        if op == 0 and n:
            i = rng.randrange(n)
            data[i] ^= 1 << rng.randrange(8)
        elif op == 1 and n:
            data[rng.randrange(n)] = rng.randrange(256)
        elif op == 2 and n:
            i = rng.randrange(n)
            del data[i:i + rng.randint(1, 16)]
        elif op == 3:
            i = rng.randint(0, n)
            data[i:i] = rng.randbytes(rng.randint(1, 16))
        elif op == 4 and n:
            i = rng.randrange(n)
            data[i:i] = data[i:i + rng.randint(1, 32)] * rng.randint(1, 4)
        elif op == 5 and n:
            del data[rng.randint(0, n):]
        elif op == 6:
            other = rng.choice(seeds)
            cut = rng.randint(0, len(other))
            data = data[:rng.randint(0, len(data))] + bytearray(other[cut:])
    return bytes(data)


def text(data: bytes) -> str:
    return data.decode("utf-8", errors="replace")


# -- targets ---------------------------------------------------------------------------
def refbox_targets() -> list[Target]:
    from rll_bt import msgs
    from rll_bt.comm import FrameCodec, MessageRegistry

    out = []
    for set_name in ("rcll2016", "rcll2025"):
        ms = msgs.message_set(set_name)
        reg = MessageRegistry.from_message_set(ms)
        samples = []
        gs = ms.GameState(game_time=ms.Time(sec=12, nsec=5), state=1, phase=30, team_cyan="Caro",
                          points_cyan=12)
        samples.append(gs)
        mi = ms.MachineInfo(team_color=0)
        mi.machines.add(name="C-BS", type="BS", state="IDLE")
        samples.append(mi)
        bs = ms.BeaconSignal(time=ms.Time(sec=1, nsec=2), seq=4, team_name="Caro", peer_name="R1",
                             team_color=0, number=1)
        samples.append(bs)
        for key in (None, "randomkey"):
            enc = FrameCodec(reg, key=key)
            seeds = [enc.encode(m) for m in samples]
            dec = FrameCodec(reg, key=key, max_frame=1024)
            label = "encrypted" if key else "plain"
            out.append(Target(f"refbox {set_name} {label}", seeds, dec.decode,
                              note="FrameCodec.decode never raises"))
    return out


def team_targets() -> list[Target]:
    from rll_bt.agenttask import link as agent_link
    from rll_bt.comm import FrameCodec
    from rll_bt.comm.framing import Drop
    from rll_bt.comm.secure import CLIENT, SERVER, SecureSession

    reg = agent_link.registry()          # the league's AgentTask and BeaconSignal, rll-bt's additions
    samples = [cls() for _ct, cls in reg if cls().IsInitialized()]
    enc = FrameCodec(reg, key="teamkey")
    seeds = [enc.encode(m) for m in samples] or [b"\x02\x02\x00\x00\x00\x00\x00\x10" + bytes(16)]
    out = [Target("team-server frames", seeds, FrameCodec(reg, key="teamkey").decode,
                  note="FrameCodec.decode never raises")]

    state: dict = {}

    def secured(data: bytes, _state=state):
        srv = _state.get("srv")
        if srv is None or _state["n"] > 50:          # a fresh session now and then
            srv, cli = SecureSession("k", SERVER), SecureSession("k", CLIENT)
            srv.open(cli.hello())
            cli.open(srv.hello())
            _state.update(srv=srv, cli=cli, n=0)
        _state["n"] += 1
        return srv.open(data)
    srv, cli = SecureSession("k", SERVER), SecureSession("k", CLIENT)
    srv.open(cli.hello())
    cli.open(srv.hello())
    sealed = [cli.seal(bytes(4) + s[12:]) for s in seeds]
    out.append(Target("team-server secured link", [cli.hello(), *sealed], secured, (Drop,),
                      note="SecureSession.open raises Drop"))
    return out


def robotino_targets() -> list[Target]:
    from backends.robotino import tags as T
    from backends.robotino.framing import FrameDecoder, encode_frame
    from backends.robotino.gripper_protocol import LineSplitter, hello_line, parse_line, status_line

    payloads = [bytes([4, 0]), bytes([17, 4, 1, 2, 3, 4]), bytes([1, 0, 3, 0]), bytes(range(40))]
    seeds = [b"".join(encode_frame(p) for p in payloads[:k + 1]) for k in range(len(payloads))]

    def serial(data: bytes):
        for ev in FrameDecoder().feed(data):
            payload = getattr(ev, "payload", None)
            if payload is not None:
                try:
                    T.decode_tags(payload)
                except T.TagError:
                    pass
    lines = [hello_line(), status_line("IDLE", 1, 2, 3, True), status_line("MOVING", -5, 0, 9000, False)]

    def gripper(data: bytes):
        for line in LineSplitter().feed(data):
            parse_line(line)
    return [Target("robotino serial frames + tags", seeds, serial,
                   note="FrameDecoder.feed never raises; decode_tags raises TagError"),
            Target("gripper lines", [b"".join(lines)] + lines, gripper, note="parse_line returns Rejected")]


def laser_targets() -> list[Target]:
    from backends.devices.laser import cola, scip

    dist = scip.encode_values([100 + i for i in range(60)], 3)
    blocks = [b"VV\n" + scip.status_line("00") + scip.info_line("VEND", "Hokuyo") + b"\n",
              b"GD0000005901\n" + scip.status_line("00") + scip.data_block(scip.encode(1234, 4) + dist),
              b"MD0000005901001\n" + scip.status_line("99") + scip.data_block(scip.encode(99, 4) + dist)]

    def urg(data: bytes):
        for block in scip.BlockReader().feed(data):
            try:
                _ = block.status
                block.info()
                block.scan(3)
            except scip.ScipError:
                pass
    scan = cola.ScanData(channels16=[cola.Channel("DIST1", 1.0, 0.0, -450000, 3333,
                                                  [500 + i for i in range(40)])])
    seeds = [cola.frame_a(cola.encode_scan_a("sRA", scan)), cola.frame_b(cola.encode_scan_b("sSN", scan)),
             cola.frame_a(b"sFA 2"), cola.frame_a(b"sAN SetAccessMode 1")]

    def tim(data: bytes):
        for tg in cola.TelegramReader().feed(data):
            try:
                (cola.decode_scan_b if tg.binary else cola.decode_scan_a)(tg.payload)
            except cola.ColaError:
                pass
    return [Target("URG SCIP 2.0 blocks", blocks, urg, note="BlockReader.feed; Block raises ScipError"),
            Target("SICK CoLa telegrams", seeds, tim, note="TelegramReader.feed; decode raises ColaError")]


def camera_targets() -> list[Target]:
    """The MJPEG part parser the camera grabber reads HTTP streams with (and the capture
    times in the parts' headers)."""
    from backends.devices.camera.mjpeg_reader import PartReader, part_timestamp

    def part(body: bytes, stamp: bytes = b"1795811291.264496") -> bytes:
        return (b"--rllbtframe\r\nContent-Type: image/jpeg\r\nContent-Length: " + str(len(body)).encode()
                + b"\r\nX-Timestamp: " + stamp + b"\r\n\r\n" + body + b"\r\n")
    seeds = [part(b"\xff\xd8jpeg\xff\xd9") * 2, part(b"") + part(b"x" * 40, b"nan"),
             b"--rllbtframe\r\nContent-Length: 3\r\n\r\nabc"]

    def parts(data: bytes):
        reader = PartReader(b"rllbtframe")
        for headers, _body in reader.feed(data[:len(data) // 2]) + reader.feed(data[len(data) // 2:]):
            part_timestamp(headers)
    return [Target("MJPEG stream parts", seeds, parts, note="PartReader.feed never raises")]


def tree_targets(tmp: Path) -> list[Target]:
    from rll_bt.tree import TreeLoadError, default_registry, parse_tree

    reg = default_registry()
    trees = sorted(Path(__file__).resolve().parents[1].joinpath("trees").rglob("*.yaml"))
    seeds = [p.read_bytes() for p in trees]

    def tree(data: bytes):
        parse_tree(tmp / "fuzz.yaml", text=text(data), registry=reg, search_path=[trees[0].parent])
    return [Target("YAML trees", seeds, tree, (TreeLoadError,), note="parse_tree raises TreeLoadError")]


def config_targets(tmp: Path) -> list[Target]:
    """The robot configuration (backends/robotino/config.py): YAML read from a file
    and checked against its schema; seeds: the module's own example and variants."""
    import textwrap

    from backends.robotino import config as robot_config
    example = textwrap.dedent(robot_config.__doc__.split("Example::", 1)[1]).strip() + "\n"
    seeds = [example, "base: {type: robotino3, device: /dev/ttyACM0}\n",
             "name: R2\nbase: {type: robotino4}\nlaser: {type: tim, host: 192.168.0.1, port: 2112}\n",
             example.replace("urg", "tim") + "faults: {}\n"]
    path = tmp / "robot.yaml"

    def load(data: bytes):
        path.write_bytes(data)
        robot_config.load_robot_config(path)
    return [Target("robot configs", [x.encode() for x in seeds], load, (robot_config.RobotConfigError,),
                   note="load_robot_config raises RobotConfigError")]


def all_targets(tmp: Path) -> list[Target]:
    out = []
    for make in (refbox_targets, team_targets, robotino_targets, laser_targets, camera_targets):
        out += make()
    return out + config_targets(tmp) + tree_targets(tmp)


def fuzz(target: Target, n: int, seed: int, report: Callable[[int], None]) -> None:
    rng = random.Random(f"{seed}/{target.name}")
    for i in range(n):
        data = mutate(rng, target.seeds)
        try:
            target.run(data)
        except target.allowed:
            target.rejected += 1
        except RecursionError as exc:
            target.escapes.append((data, f"RecursionError: {exc}"))
        except Exception as exc:
            target.escapes.append((data, "".join(traceback.format_exception_only(exc)).strip()))
        if i % 1000 == 999:
            report(i + 1)


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=Path(__file__).parent, check=False).stdout.strip() or "?"
    except OSError:
        return "?"


def main(argv: Iterable[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=100_000, help="inputs per decoder (default 100000)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the inputs (default 1)")
    ap.add_argument("--only", metavar="TEXT", help="only decoders whose name contains TEXT")
    ap.add_argument("--show", type=int, default=3, help="escapes to print per decoder (default 3)")
    args = ap.parse_args(list(argv) if argv is not None else None)
    with tempfile.TemporaryDirectory() as tmpdir:
        targets = [t for t in all_targets(Path(tmpdir))
                   if not args.only or args.only.lower() in t.name.lower()]
        if not targets:
            print(f"no decoder matches {args.only!r}", file=sys.stderr)
            return 2
        rows = []
        for t in targets:
            t0 = time.perf_counter()

            def report(done, t=t, t0=t0):
                rate = done / max(time.perf_counter() - t0, 1e-9)
                print(f"\r{t.name:<34} {done:>7}/{args.n}  {rate:8.0f}/s  escapes {len(t.escapes)}",
                      end="", file=sys.stderr, flush=True)
            fuzz(t, args.n, args.seed, report)
            print(file=sys.stderr)
            rows.append((t, time.perf_counter() - t0))
    print(f"\nfuzz at {commit()}: {args.n} inputs per decoder, seed {args.seed}")
    print(f"{'decoder':<34} {'inputs':>8} {'rejected':>9} {'escapes':>8} {'s':>7}  contract")
    for t, secs in rows:
        print(f"{t.name:<34} {args.n:>8} {t.rejected:>9} {len(t.escapes):>8} {secs:7.1f}  {t.note}")
    total = sum(len(t.escapes) for t, _ in rows)
    for t, _ in rows:
        for data, what in t.escapes[:args.show]:
            print(f"\n{t.name}: {what}\n  input ({len(data)} bytes): {data[:120]!r}")
    print(f"\n{total} escapes in {len(rows)} decoders (aim 0)")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
