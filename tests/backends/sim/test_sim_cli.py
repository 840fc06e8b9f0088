import json

from rll_bt.cli import main


def test_sim_world_writes_a_png(tmp_path, capsys):
    out = tmp_path / "field.png"
    assert main(["sim", "world", "--profile", "rcll2016", "--seed", "4", "--png", str(out)]) == 0
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000
    text = capsys.readouterr().out
    assert "C-BS" in text and "Z9" in text and "65/66" in text


def test_sim_world_json_matches_the_generator(capsys):
    from backends.sim.layout import generate_layout
    assert main(["sim", "world", "--profile", "rcll2025", "--seed", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == generate_layout("rcll2025", 2).to_dict()


def test_sim_world_bad_input_and_no_display(tmp_path, monkeypatch, capsys):
    assert main(["sim", "world", "--profile", "rcll1999"]) == 2
    assert "rcll1999" in capsys.readouterr().err
    assert main(["sim", "world", "--png", str(tmp_path / "missing" / "f.png")]) == 2
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["sim", "world", "--gui"]) == 3
    assert "no display" in capsys.readouterr().err
