"""Halting: a preempted branch is halted before the new one starts, and an
interrupted parent terminates its running children."""
from rll_bt.tree import Status


def test_halt_before_start_in_priority_switch(make):
    tree, ev = make("""
        blackboard:
          obstacle: bool          # written from outside the tree (this test)
        root:
          reactive_selector:
            - reactive_sequence:
                - check_blackboard: {condition: "obstacle == true"}
                - probe: {tag: evade, script: R}
            - sequence_with_memory:
                - probe: {tag: drive, script: R}
        """)
    tree.tick()
    tree.tick()
    tree.blackboard.set("/obstacle", True)
    tree.tick()
    # plain py_trees would record evade:start before drive:halt
    assert ev == ["drive:start", "drive:halt", "evade:start"]
    tree.blackboard.set("/obstacle", False)
    tree.tick()
    assert ev[-2:] == ["evade:halt", "drive:start"]


def test_interrupt_terminates_every_running_node(make):
    tree, ev = make("""
        root:
          parallel:
            policy: all
            synchronise: false
            children:
              - retry: {attempts: 3, child: {probe: {tag: a, script: R}}}
              - timeout: {seconds: 10, child: {subtree: {file: s.yaml}}}
        """, files={"s.yaml": "root:\n  recovery: {action: {probe: {tag: b, script: R}}, recoveries: [success]}\n"})
    tree.tick()
    tree.interrupt()
    assert sorted(ev) == ["a:halt", "a:start", "b:halt", "b:start"]
    assert all(i.behaviour.status is Status.INVALID for i in tree.nodes)


def test_run_interrupts_when_max_ticks_reached(make):
    tree, ev = make("root:\n  probe: {tag: x, script: R}\n")
    assert tree.run(hz=10, max_ticks=3) is Status.RUNNING
    assert ev == ["x:start", "x:halt"]
