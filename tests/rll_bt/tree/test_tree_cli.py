"""`rll-bt tree validate|show|nodes|run|replay|schema` against the scripted backend."""
import json
from pathlib import Path

from rll_bt.cli import main
from tests.support import TREES

DATA = Path(__file__).parent / "data"


def test_validate(capsys):
    assert main(["tree", "validate", str(DATA / "grab.yaml"), str(DATA / "fail.yaml")]) == 0
    assert "grab.yaml: ok (10 nodes, 1 subtree file(s))" in capsys.readouterr().out
    assert main(["tree", "validate", str(DATA / "grab.yaml"), str(DATA / "bad.yaml")]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml:3:7: unknown node type 'wiat'" in err and "bad.yaml:4:13: unknown port 'mesage'" in err
    assert "1 of 2 file(s) invalid" in err
    assert main(["tree", "validate", str(DATA / "nope.yaml")]) == 2
    assert main(["tree", "validate", "--task", "station=C-BS", str(DATA / "grab.yaml")]) == 0


def test_show(capsys, tmp_path):
    assert main(["tree", "show", str(DATA / "grab.yaml")]) == 0
    out = capsys.readouterr().out
    assert "recovery 'grab'" in out and "subtree 'fix'" in out and "[recoveries]" in out
    assert main(["tree", "show", "--dot", str(DATA / "grab.yaml")]) == 0
    dot = capsys.readouterr().out
    assert dot.startswith('digraph "grab_demo"') and dot.count("->") == 9
    png = tmp_path / "t.png"
    assert main(["tree", "show", "--png", str(png), str(DATA / "grab.yaml")]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["tree", "show", str(DATA / "bad.yaml")]) == 2
    assert main(["tree", "show", str(TREES / "explore_zone.yaml")]) == 0
    assert "output found: list -> /found" in capsys.readouterr().out
    assert main(["tree", "nodes", "subtree", "recovery"]) == 0
    out = capsys.readouterr().out
    assert "pass: any" in out and "on_recovery_failure: str (default \"escalate\"; one of escalate, retry, fail" in out


def test_nodes(capsys):
    assert main(["tree", "nodes"]) == 0
    out = capsys.readouterr().out
    for t in ("reactive_sequence", "sequence_with_memory", "recovery", "retry", "guard", "wait", "fail_with_error"):
        assert f"\n{t}  [" in "\n" + out
    assert main(["tree", "nodes", "--json"]) == 0
    items = {d["name"]: d for d in json.loads(capsys.readouterr().out)}
    assert [p["name"] for p in items["retry"]["ports"]] == ["attempts", "delay", "backoff", "max_delay", "attempt"]
    assert items["wait"]["ports"][0]["type"] == "float" and items["wait"]["doc"]
    assert main(["tree", "nodes", "wiat"]) == 2


def test_run_success_failure_and_replay(capsys, tmp_path):
    log = tmp_path / "ticks.jsonl"
    rc = main(["tree", "run", str(DATA / "grab.yaml"), "--backend", "scripted", "--task", "station=C-BS",
               "--clock", "sim", "--hz", "10", "--log", str(log), "-q"])
    assert rc == 0
    assert "SUCCESS" in capsys.readouterr().out
    lines = [json.loads(x) for x in log.read_text().splitlines()]
    assert lines[0]["kind"] == "tree" and all(r["kind"] == "tick" for r in lines[1:])
    assert any(r.get("bb", {}).get("/holding") is True for r in lines[1:])
    assert main(["tree", "replay", str(log), "--state"]) == 0
    out = capsys.readouterr().out
    assert "tick 1  t=0.000  RUNNING" in out and "bb /holding = true" in out and "state after tick" in out
    rc = main(["tree", "run", str(DATA / "fail.yaml"), "--backend", "scripted", "--clock", "sim", "-q"])
    assert rc == 1 and "FAILURE after 3 ticks (NO_LUCK" in capsys.readouterr().out


def test_run_argument_errors(capsys):
    assert main(["tree", "run", str(DATA / "grab.yaml"), "--backend", "scripted", "--clock", "sim"]) == 2
    assert "the task does not give the required field 'station'" in capsys.readouterr().err
    assert main(["tree", "run", str(DATA / "grab.yaml"), "--backend", "nosuch", "--task", "station=x"]) == 2
    assert main(["tree", "run", str(DATA / "grab.yaml"), "--backend", "scripted", "--task", "statoin=x",
                 "--task", "station=y"]) == 2
    assert "did you mean 'station'" in capsys.readouterr().err
    rc = main(["tree", "run", str(DATA / "grab.yaml"), "--backend", "scripted", "--task", "station=x",
               "--clock", "sim", "--max-ticks", "1", "-q"])
    assert rc == 1 and "--max-ticks" in capsys.readouterr().out


def test_schema_command_and_shipped_schema_is_current(capsys, tmp_path):
    from rll_bt.tree.schemagen import SHIPPED, schema_text
    assert SHIPPED.read_text() == schema_text(builtin_only=True), "regenerate rll_bt/tree/schema/tree.schema.json"
    assert main(["tree", "schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    names = {next(iter(e["properties"])) for e in schema["$defs"]["node"]["anyOf"][1:]}
    assert {"recovery", "parallel", "subtree", "guard"} <= names
    out = tmp_path / "builtin.json"
    assert main(["tree", "schema", "--builtin", "-o", str(out)]) == 0
    assert out.read_text() == SHIPPED.read_text()
