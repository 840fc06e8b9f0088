"""``rll-bt robotino emulate|probe|drive``."""
import json

import pytest

from backends.robotino.emulator import RobotinoEmulator
from rll_bt.cli import main


@pytest.fixture
def emu():
    with RobotinoEmulator(gripper=True) as e:
        yield e


def test_probe_unreachable_exits_3(tmp_path, capsys):
    assert main(["robotino", "probe", "--device", str(tmp_path / "ttyACM7")]) == 3
    err = capsys.readouterr().err
    assert "cannot open serial device" in err and "Traceback" not in err


def test_probe_prints_versions_battery_bumper_motors(emu, capsys):
    assert main(["robotino", "probe", "--device", emu.device]) == 0
    out = capsys.readouterr().out
    assert "hardware 3.0.0, firmware 1.2.3" in out
    assert "battery  24.50 V" in out and "bumper   free" in out and "motors   speed [0, 0, 0, 0]" in out


def test_probe_json_with_gripper(emu, capsys):
    assert main(["robotino", "probe", "--device", emu.device, "--gripper-device", emu.gripper_device,
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["firmware_version"] == "1.2.3" and report["battery"]["voltage"] == 24.5
    assert len(report["distance_sensors_v"]) == 9 and report["gripper"]["state"] in ("idle", "moving")


def test_drive_moves_the_robot(emu, capsys):
    assert main(["robotino", "drive", "--device", emu.device, "--vx", "0.2", "--seconds", "0.4"]) == 0
    out = capsys.readouterr().out
    assert "stopped" in out and "0 link losses" in out
    x, y, _ = emu.ground_truth()
    assert 0.03 < x < 0.12 and abs(y) < 0.01


@pytest.mark.parametrize("args", [["--seconds", "0"], ["--vx", "3"], ["--seconds", "500"]])
def test_drive_rejects_out_of_range_values(args, capsys):
    assert main(["robotino", "drive", "--device", "/nonexistent", *args]) == 2
    err = capsys.readouterr().err
    assert "rll-bt: error:" in err and "Traceback" not in err


def test_drive_rejects_non_numbers(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["robotino", "drive", "--omega", "nan"])
    assert exc.value.code == 2 and "must be finite" in capsys.readouterr().err


def test_emulate_runs_and_reports(tmp_path, capsys):
    assert main(["robotino", "emulate", "--gripper", "--duration", "0.3", "--report", "0.1",
                 "--link-dir", str(tmp_path), "--seed", "3", "--corrupt", "0.01"]) == 0
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert lines[:2] == [f"{tmp_path}/robotino-base", f"{tmp_path}/robotino-gripper"]
    assert lines[-1].startswith("summary: {")
    assert "gripper:" in captured.err and "t=" in captured.err
    assert not (tmp_path / "robotino-base").exists()       # unplugged on exit


def test_emulate_rejects_bad_probability(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["robotino", "emulate", "--corrupt", "1.5"])
    assert exc.value.code == 2
    assert "probability" in capsys.readouterr().err


@pytest.mark.parametrize("sub", ["emulate", "probe", "drive"])
def test_help(sub, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["robotino", sub, "--help"])
    assert exc.value.code == 0 and "usage" in capsys.readouterr().out


@pytest.mark.parametrize("signame", ["SIGINT", "SIGTERM"])
def test_emulate_process_stops_on_a_signal_with_its_summary(signame):
    """Started as a background job (SIGINT ignored, as a non-interactive shell
    starts one), the emulator still stops on SIGINT, and on SIGTERM, and
    prints its summary."""
    import signal
    import subprocess
    import sys

    cmd = [sys.executable, "-c", "import sys; from rll_bt.cli import main; sys.exit(main())",
           "robotino", "emulate"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN))
    try:
        device = proc.stdout.readline().strip()
        assert device.endswith("robotino-base")
        proc.send_signal(getattr(signal, signame))
        out, _ = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0
    assert out.splitlines()[-1].startswith("summary: {")
