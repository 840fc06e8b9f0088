"""``rll-bt vision light|tags``: output formats, camera files and bad input."""
import json
import math

import cv2
import numpy as np
import pytest

from backends.sim import World
from rll_bt.backend import Pose2D
from rll_bt.cli import main
from rll_bt.errors import UserError
from skills.perception.camera_file import load_camera, scaled


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """A rendered 640x480 view of C-BS's output face (red + green on) and its camera file."""
    d = tmp_path_factory.mktemp("vision")
    with World("rcll2016", seed=2, perception="rendered") as w:
        robot = w.add_robot("CYAN", 1, camera_width=640, camera_height=480)
        w.set_lights("C-BS", red="ON", green="ON")
        st = w.station("C-BS")
        centre, frame = st.tag_frame("output")
        a = math.atan2(frame[1, 2], frame[0, 2])
        cx, cy = centre[0] + 1.5 * math.cos(a), centre[1] + 1.5 * math.sin(a)
        w.teleport("CYAN", 1, Pose2D(cx - 0.2 * math.cos(a + math.pi), cy - 0.2 * math.sin(a + math.pi), a + math.pi))
        w.step(0.02)
        img = w.camera_image(robot)
        path = d / "view.png"
        cv2.imwrite(str(path), img.image)
        k = img.intrinsics
        cam = d / "camera.yaml"
        cam.write_text(f"width: {k.width}\nheight: {k.height}\nfx: {k.fx}\nfy: {k.fy}\ncx: {k.cx}\ncy: {k.cy}\n"
                       "distortion: [0, 0, 0, 0, 0]\n")
        return path, cam, st.tag_id("output"), 1.5


def test_light_json_format(rendered, capsys):
    path, _, _, _ = rendered
    free = path.parent / "free.png"
    cv2.imwrite(str(free), np.full((480, 640, 3), 128, np.uint8))
    assert main(["vision", "light", str(path), str(free), "--json"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2
    first, second = (json.loads(line) for line in lines)
    assert first["image"] == str(path) and isinstance(first["ms"], float)
    det = first["detections"][0]
    assert set(det) == {"box", "score", "state", "lights", "probabilities"}
    assert len(det["box"]) == 4 and all(isinstance(v, int) for v in det["box"])
    assert det["state"] == 5
    assert det["lights"] == {"red": "on", "yellow": "off", "green": "on"}
    assert len(det["probabilities"]) == 8 and abs(sum(det["probabilities"]) - 1.0) < 1e-3
    scores = [d["score"] for d in first["detections"]]
    assert scores == sorted(scores, reverse=True)
    assert second == {"image": str(free), "ms": second["ms"], "detections": []}


def test_light_region_and_text_output(rendered, capsys):
    path, _, _, _ = rendered
    assert main(["vision", "light", str(path), "--region", "0,0,60,60"]) == 0
    assert "no signal tower" in capsys.readouterr().out


def test_unreadable_image_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"not a png")
    assert main(["vision", "light", str(bad), "--json"]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "Traceback" not in err
    assert main(["vision", "light", str(tmp_path / "missing.png")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_missing_models_directory_is_a_clear_error(rendered, tmp_path, capsys):
    path, _, _, _ = rendered
    assert main(["vision", "light", str(path), "--models", str(tmp_path)]) == 2
    assert "model file missing" in capsys.readouterr().err


def test_tags_json(rendered, capsys):
    path, cam, tag_id, distance = rendered
    assert main(["vision", "tags", str(path), "--camera", str(cam), "--json"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[0])
    tags = {t["id"]: t for t in out["tags"]}
    assert tag_id in tags
    t = tags[tag_id]
    assert t["machine"] == "C-BS" and t["side"] == "OUTPUT"
    assert t["distance"] == pytest.approx(distance, abs=0.06)
    assert abs(t["yaw_deg"]) < 5.0
    assert len(t["corners"]) == 4


def test_camera_file_errors(tmp_path):
    f = tmp_path / "cam.yaml"
    f.write_text("width: 640\nheight: 480\nfx: 500\n")
    with pytest.raises(UserError, match="missing key"):
        load_camera(f)
    f.write_text("width: 640\nheight: 480\nfx: 500\nfy: -1\ncx: 320\ncy: 240\n")
    with pytest.raises(UserError, match="fy must be a positive number"):
        load_camera(f)
    j = tmp_path / "cam.json"
    j.write_text(json.dumps({"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240,
                             "distortion": [0.1, 0, 0, 0]}))
    k = load_camera(j)
    assert k.distortion == (0.1, 0.0, 0.0, 0.0)
    half = scaled(k, 320, 240)
    assert (half.fx, half.cx) == (250.0, 160.0)
    with pytest.raises(UserError, match="cannot read"):
        load_camera(tmp_path / "nope.yaml")


def test_tags_with_a_bad_camera_file_exits_2(rendered, tmp_path, capsys):
    path, _, _, _ = rendered
    f = tmp_path / "cam.yaml"
    f.write_text("[1, 2]\n")
    assert main(["vision", "tags", str(path), "--camera", str(f)]) == 2
    assert "camera file" in capsys.readouterr().err


def test_min_confidence_must_be_a_probability(rendered, capsys):
    path, _, _, _ = rendered
    with pytest.raises(SystemExit) as exc:
        main(["vision", "light", str(path), "--min-confidence", "1.5"])
    assert exc.value.code == 2
    assert "between 0 and 1" in capsys.readouterr().err
    assert main(["vision", "light", str(path), "--json", "--min-confidence", "1"]) == 0
    assert json.loads(capsys.readouterr().out)["detections"] == []     # no reading is that sure


def test_train_physical_without_a_directory_for_its_file_is_bad_usage(tmp_path, capsys):
    assert main(["vision", "train-physical", "--out", str(tmp_path / "no" / "such" / "model.npz")]) == 2
    assert "no directory" in capsys.readouterr().err
