"""$task and $param values: filled, type-checked, required, converted from text."""
import pytest

from rll_bt.tree import CliText, Status, TreeLoadError

TREE = """
    task:
      zone: {type: str, doc: zone to explore}
      side: {type: str, choices: [input, output], default: input}
      attempts: {type: int, default: 2}
    params:
      speed: {type: float, default: 0.5}
    root:
      reactive_sequence:
        - set_blackboard: {key: $bb.zone, value: $task.zone}
        - set_blackboard: {key: $bb.side, value: $task.side}
        - set_blackboard: {key: $bb.speed, value: $param.speed}
        - retry: {attempts: $task.attempts, child: success}
    """


def test_task_and_params_are_filled(make):
    tree, _ = make(TREE, task={"zone": "C_Z12"}, params={"speed": 1})
    assert tree.tick() is Status.SUCCESS
    assert tree.blackboard.snapshot() == {"/zone": "C_Z12", "/side": "input", "/speed": 1.0}
    assert tree.ctx.task["zone"] == "C_Z12"


def test_missing_and_mistyped_task_fields(make):
    with pytest.raises(TreeLoadError) as e:
        make(TREE, task={})
    assert "tree.yaml:3:3: the task does not give the required field 'zone'" in str(e.value)
    with pytest.raises(TreeLoadError) as e:
        make(TREE, task={"zone": 12, "side": "top"})
    text = str(e.value)
    assert "task field 'zone': expected str, got int 12" in text
    assert "task field 'side': expected one of input, output; got 'top'" in text


def test_command_line_text_is_converted_to_declared_types(make):
    tree, _ = make(TREE, task={"zone": CliText("C_Z12"), "attempts": CliText("3")}, params={"speed": CliText("2")})
    tree.tick()
    assert tree.blackboard.get("/speed") == 2.0 and tree.root.children[3].attempts == 3


def test_validation_without_task_keeps_references_symbolic(check):
    assert check(TREE) == []
    errs = check("task:\n  zone: str\nroot:\n  wait: {seconds: $task.zone}\n")
    assert "port 'seconds' of 'wait' expects float but $task.zone is str" in errs[0]
