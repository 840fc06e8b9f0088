"""Sequences and selectors with and without memory, and parallel policies."""
from rll_bt.tree import Status
from tests.support.trees import tick_n


def test_reactive_sequence_rechecks_condition_and_halts_running_child(make):
    tree, ev = make("""
        root:
          reactive_sequence:
            - check_blackboard: {condition: "go == true"}
            - probe: {tag: work, script: R}
        blackboard:
          go: {type: bool, default: true}
        """)
    assert tick_n(tree, 3) is Status.RUNNING
    assert ev == ["work:start"]
    tree.blackboard.set("/go", False)
    assert tree.tick() is Status.FAILURE
    assert ev == ["work:start", "work:halt"]


def test_sequence_with_memory_does_not_recheck(make):
    tree, ev = make("""
        root:
          sequence_with_memory:
            - check_blackboard: {condition: "go == true"}
            - probe: {tag: work, script: RRRS}
        blackboard:
          go: {type: bool, default: true}
        """)
    tree.tick()
    tree.blackboard.set("/go", False)
    assert tick_n(tree, 3) is Status.SUCCESS
    assert ev == ["work:start", "work:end"]


def test_reactive_selector_switches_to_higher_priority(make):
    tree, ev = make("""
        blackboard:
          alarm: bool          # written from outside the tree (this test)
        root:
          reactive_selector:
            - reactive_sequence:
                - check_blackboard: {condition: alarm}
                - probe: {tag: high, script: R}
            - probe: {tag: low, script: R}
        """)
    tick_n(tree, 2)
    assert ev == ["low:start"]
    tree.blackboard.set("/alarm", True)
    tree.tick()
    assert ev == ["low:start", "low:halt", "high:start"]


def test_selector_with_memory_keeps_running_child(make):
    tree, ev = make("""
        blackboard:
          alarm: bool          # written from outside the tree (this test)
        root:
          selector_with_memory:
            - reactive_sequence:
                - check_blackboard: {condition: alarm}
                - probe: {tag: high, script: R}
            - probe: {tag: low, script: RRS}
        """)
    tree.tick()
    tree.blackboard.set("/alarm", True)
    assert tick_n(tree, 2) is Status.SUCCESS
    assert ev == ["low:start", "low:end"]


def _parallel(policy_lines):
    return f"""
        root:
          parallel:
            {policy_lines}
            children:
              - probe: {{tag: a, script: S, name: a}}
              - probe: {{tag: b, script: RRS, name: b}}
              - probe: {{tag: c, script: R, name: c}}
        """


def test_parallel_all_synchronised_skips_finished_children(make):
    tree, ev = make(_parallel("policy: all\n            synchronise: true"))
    tick_n(tree, 3)
    assert ev.count("a:start") == 1       # a succeeded once and is not re-ticked
    assert tree.status is Status.RUNNING  # c never finishes


def test_parallel_all_unsynchronised_reticks_finished_children(make):
    tree, ev = make(_parallel("policy: all\n            synchronise: false"))
    tick_n(tree, 3)
    assert ev.count("a:start") == 3


def test_parallel_one_succeeds_at_first_success_and_halts_the_rest(make):
    tree, ev = make(_parallel("policy: one"))
    assert tree.tick() is Status.SUCCESS
    assert "b:halt" in ev and "c:halt" in ev


def test_parallel_selected(make):
    tree, ev = make(_parallel("policy: selected\n            synchronise: true\n            selected: [a, b]"))
    assert tick_n(tree, 2) is Status.RUNNING
    assert tree.tick() is Status.SUCCESS
    assert "c:halt" in ev


def test_parallel_failure_fails(make):
    tree, ev = make("""
        root:
          parallel:
            policy: all
            synchronise: false
            children: [{probe: {tag: a, script: R}}, failure]
        """)
    assert tree.tick() is Status.FAILURE
    assert ev == ["a:start", "a:halt"]


def test_parallel_policy_needs_explicit_synchronise(check):
    errs = check(_parallel("policy: all"))
    assert len(errs) == 1 and "needs `synchronise: true|false` (no default)" in errs[0]
    assert "tree.yaml:3:3: parallel" in errs[0]
    errs = check(_parallel("policy: one\n            synchronise: true"))
    assert "policy 'one' has no `synchronise`" in errs[0]
    errs = check(_parallel("policy: selected\n            synchronise: true\n            selected: [a, d]"))
    assert "no child named 'd'" in errs[0]


def test_plain_sequence_is_ambiguous(check):
    errs = check("root:\n  sequence: [success]\n")
    assert ":2:3: unknown node type 'sequence'" in errs[0]
    assert "sequence_with_memory" in errs[0] and "reactive_sequence" in errs[0]
