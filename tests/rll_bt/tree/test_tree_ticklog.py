"""The JSON-lines tick log records visited nodes, halts and blackboard changes."""
import io
import json

from rll_bt.tree.ticklog import TickLogger, format_log, jsonable, replay


def test_tick_log_records_and_replays(make, tmp_path):
    tree, _ = make("""
        blackboard:
          go: bool          # written from outside the tree (this test)
        root:
          reactive_selector:
            - reactive_sequence:
                - check_blackboard: {condition: go}
                - set_blackboard: {key: $bb.seen, value: 1}
                - probe: {tag: a, script: R}
            - probe: {tag: b, script: R}
        """)
    buf = io.StringIO()
    log = TickLogger(tree, buf)
    tree.tick()
    tree.blackboard.set("/go", True)
    tree.tick()
    tree.blackboard.unset("/go")
    tree.tick()
    log.close()
    recs = [json.loads(x) for x in buf.getvalue().splitlines()]
    header, ticks = recs[0], recs[1:]
    names = {n["id"]: n["name"] for n in header["nodes"]}
    assert [names[i] for i, _ in ticks[0]["visited"]] == ["check_blackboard", "reactive_sequence", "probe",
                                                        "reactive_selector"]
    assert ticks[1]["bb"] == {"/go": True, "/seen": 1}
    assert [names[i] for i in ticks[1]["halted"]] == ["probe"]
    assert ticks[2]["unset"] == ["/go"] and "bb" not in ticks[2]
    assert [names[i] for i, _ in ticks[2]["visited"]][-2:] == ["probe", "reactive_selector"]   # b runs now
    states = list(replay(header, ticks))
    assert states[-1][1] == {"/seen": 1}
    text = "\n".join(format_log(header, ticks, show_tree=True))
    assert "halted: probe 'probe'" in text and "bb /go = true" in text


def test_jsonable():
    from rll_bt.backend import Pose2D
    assert jsonable(Pose2D(1, 2, 0.5)) == {"x": 1, "y": 2, "theta": 0.5}
    assert jsonable(float("nan")) == "nan" and jsonable({1: (1, 2)}) == {"1": [1, 2]}
    assert isinstance(jsonable(object()), str)
