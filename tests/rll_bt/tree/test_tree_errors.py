"""Malformed trees give file:line:col messages with hints."""
import re


def test_unknown_node_type(check):
    errs = check("root:\n  reactive_sequence:\n    - chek_blackboard: {condition: x}\n")
    assert errs == [errs[0]] and re.search(r"tree\.yaml:3:7: unknown node type 'chek_blackboard'", errs[0])
    assert "did you mean 'check_blackboard'" in errs[0]


def test_missing_mistyped_and_unknown_ports(check):
    errs = check("""
        root:
          reactive_sequence:
            - wait: {}
            - wait: {seconds: two}
            - wait: {secnds: 1}
            - log: {message: hi, level: loud}
        """)
    text = "\n".join(errs)
    assert "tree.yaml:4:7: node type 'wait' requires port 'seconds' (float)" in text
    assert "tree.yaml:5:23: port 'seconds' of 'wait': expected float, got str 'two'" in text
    assert "tree.yaml:6:14: unknown port 'secnds' for node type 'wait'" in text and "did you mean 'seconds'" in text
    assert "tree.yaml:7:33: port 'level' of 'log': expected one of debug, info, warning, error" in text
    assert len(errs) == 5       # every error is reported (the missing port twice: line 6 lacks it too)


def test_bad_indentation_yaml_syntax(check):
    errs = check("root:\n  reactive_sequence:\n    children:\n      - success\n     - failure\n")
    assert len(errs) == 1
    assert errs[0].startswith(errs[0].split("tree.yaml")[0] + "tree.yaml:5:6: YAML:")
    assert "hint: check the indentation" in errs[0]


def test_children_not_indented_under_type(check):
    errs = check("root:\n  reactive_sequence:\n  children: [success]\n")
    assert "tree.yaml:3:3: 'children' is not indented under 'reactive_sequence'" in errs[0]


def test_bad_references(check):
    errs = check("task:\n  zone: str\nroot:\n  log: {message: $task.zon}\n")
    assert "tree.yaml:4:18: unknown task field 'zon' in $task.zon" in errs[0] and "did you mean 'zone'" in errs[0]
    errs = check("root:\n  log: {message: $foo.bar}\n")
    assert "unknown reference '$foo.bar'" in errs[0]
    errs = check("root:\n  log: {message: $param.x}\n")
    assert "unknown parameter 'x'" in errs[0]
    errs = check("root:\n  log: {message: $bb.a.b}\n")
    assert "'a.b' is not a valid blackboard key" in errs[0]
    errs = check("root:\n  set_blackboard: {key: out, value: 1}\n")
    assert "output port 'key' of 'set_blackboard' must be bound to a blackboard key" in errs[0]
    errs = check("root:\n  retry: {attempts: $bb.n, child: success}\n")
    assert "takes a value fixed when the tree loads" in errs[0]


def test_expression_error_points_into_the_condition(check):
    errs = check('root:\n  check_blackboard: {condition: "a == 1 and b.c"}\n')
    assert "tree.yaml:2:46: port 'condition' of 'check_blackboard': unexpected character '.'" in errs[0]


def test_header_and_file_level_errors(check, tmp_path):
    errs = check("rooot:\n  success\n")
    assert any("tree.yaml:1:1: unknown top-level key 'rooot'" in e and "did you mean 'root'" in e for e in errs)
    assert "the file is empty" in check("")[0]
    assert "the tree has no `root:`" in check("name: x\n")[0]
    errs = check("task:\n  zone: strr\nroot: success\n")
    assert "unknown type 'strr'" in errs[0] and "did you mean 'str'" in errs[0]


def test_blackboard_key_types_are_checked_at_load(check):
    errs = check("""
        blackboard:
          speed: {type: str, default: fast}
        root:
          wait: {seconds: $bb.speed}
        """)
    assert "port 'seconds' of 'wait' expects float but blackboard key /speed holds str" in errs[0]
    errs = check("""
        root:
          reactive_sequence:
            - set_blackboard: {key: $bb.n, value: 1}
            - set_blackboard: {key: $bb.n, value: one}
        """)
    assert "writes str to /n" in errs[0]


def test_control_characters_are_a_yaml_error_not_a_crash(check):
    # found by benchmarks/fuzz.py: PyYAML's reader refuses them before parsing starts
    errs = check("root:\n  wait: {seconds: 1}\x18\n")
    assert len(errs) == 1 and "YAML" in errs[0]


def test_a_condition_port_may_start_with_a_reference(make):
    """`check_blackboard: {condition: "$param.gain > 0.1"}` is a condition,
    not a reference named `gain > 0.1`."""
    from rll_bt.tree import Status
    text = ("params: {gain: {type: float, default: 0.5}}\n"
            "root:\n  check_blackboard: {condition: \"$param.gain > 0.1\"}\n")
    tree, _ = make(text)
    assert tree.tick() is Status.SUCCESS
    tree, _ = make(text, params={"gain": 0.05}, name="low.yaml")
    assert tree.tick() is Status.FAILURE
