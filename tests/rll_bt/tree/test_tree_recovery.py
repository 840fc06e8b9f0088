"""The recovery block: escalation order, retries per level, final error code."""
from rll_bt.tree import Status

TREE = """
    root:
      recovery:
        name: grab
        retries: {retries}
        error_code: GRASP_FAILED
        error_message: no workpiece in the gripper
        level: $bb.level
        action: {{probe: {{tag: act, script: {act}}}}}
        recoveries:
          - probe: {{tag: realign, script: {r1}}}
          - probe: {{tag: relocalise, script: {r2}}}
    """


def _run(tree):
    status = tree.run(hz=10, max_ticks=100)
    return status, [e for e in tree.ctx.services["events"] if e.endswith(":start")]


def test_escalation_order_and_final_error_code(make):
    tree, _ = make(TREE.format(retries=2, act="F", r1="S", r2="S"))
    status, starts = _run(tree)
    assert status is Status.FAILURE
    assert starts == ["act:start",
                      "realign:start", "act:start", "realign:start", "act:start",
                      "relocalise:start", "act:start", "relocalise:start", "act:start"]
    err = tree.error()
    assert (err.code, err.message, err.node) == ("GRASP_FAILED", "no workpiece in the gripper", "grab")
    assert tree.root.history[-1] == "action@2"


def test_recovery_success_clears_error_and_reports_level(make):
    tree, ev = make(TREE.format(retries=1, act="F", r1="S", r2="S"))
    act = tree.find("probe")
    tree.blackboard.set("/error/code", "OLD")
    # the action fails twice, then succeeds: after level 2
    scripts = iter(["F", "F", "S"])
    orig_init = act.initialise

    def init():
        orig_init()
        act._bindings["script"].value = next(scripts)
    act.initialise = init
    status, starts = _run(tree)
    assert status is Status.SUCCESS
    assert starts == ["act:start", "realign:start", "act:start", "relocalise:start", "act:start"]
    assert tree.blackboard.get("/level") == 2
    assert tree.error() is None


def test_failed_recovery_escalates_at_once(make):
    tree, _ = make(TREE.format(retries=3, act="F", r1="F", r2="S"))
    status, starts = _run(tree)
    assert status is Status.FAILURE
    assert starts[:4] == ["act:start", "realign:start", "relocalise:start", "act:start"]
    assert starts.count("realign:start") == 1 and starts.count("relocalise:start") == 3


def test_recovery_needs_action_and_recoveries(check):
    errs = check("root:\n  recovery: {action: success}\n")
    assert "recovery needs `recoveries:`" in errs[0]
    errs = check("root:\n  recovery: {retries: 0, action: success, recoveries: [success]}\n")
    assert "`retries` must be at least 1" in errs[0]


POLICY = """
    root:
      recovery:
        name: grab
        on_recovery_failure: {policy}
        error_code: GRASP_FAILED
        action: {{probe: {{tag: act, script: F}}}}
        recoveries:
          - probe: {{tag: realign, script: F}}
          - probe: {{tag: relocalise, script: F}}
    """


def test_policy_retry_tries_the_action_again_after_a_failed_recovery(make):
    """What a `force_success` around each recovery did: every level gets its
    round and the action is tried after each, failed recovery or not."""
    tree, _ = make(POLICY.format(policy="retry"))
    status, starts = _run(tree)
    assert status is Status.FAILURE
    assert starts == ["act:start", "realign:start", "act:start", "relocalise:start", "act:start"]
    assert tree.error().code == "GRASP_FAILED"


def test_policy_retry_is_tick_for_tick_what_force_success_wrappers_did(make):
    wrapped = """
        root:
          recovery:
            action: {probe: {tag: act, script: RF}}
            recoveries:
              - force_success: {child: {probe: {tag: r1, script: RRF}}}
              - force_success: {child: {probe: {tag: r2, script: RS}}}
        """
    policy = """
        root:
          recovery:
            on_recovery_failure: retry
            action: {probe: {tag: act, script: RF}}
            recoveries:
              - probe: {tag: r1, script: RRF}
              - probe: {tag: r2, script: RS}
        """
    traces = []
    for text in (wrapped, policy):
        tree, events = make(text)
        statuses = [tree.tick() for _ in range(20)]
        traces.append((statuses, list(events), tree.root.history))
    assert traces[0] == traces[1]


def test_policy_escalate_is_the_default(make):
    tree, _ = make(POLICY.format(policy="escalate"))
    _status, starts = _run(tree)
    default = "\n".join(line for line in POLICY.splitlines() if "on_recovery_failure" not in line)
    tree2, _ = make(default.format(policy="-"))
    _status2, starts2 = _run(tree2)
    assert starts == starts2 == ["act:start", "realign:start", "relocalise:start"]


def test_policy_fail_fails_the_node_at_the_first_failed_recovery(make):
    tree, _ = make(POLICY.format(policy="fail"))
    status, starts = _run(tree)
    assert status is Status.FAILURE
    assert starts == ["act:start", "realign:start"]
    assert tree.error().code == "GRASP_FAILED"
    assert "recovery level 1 (probe) failed" in tree.root.feedback_message


def test_unknown_policy_is_reported_with_its_place(check):
    errs = check("root:\n  recovery: {on_recovery_failure: ignore, action: success, recoveries: [success]}\n")
    assert ":2:35:" in errs[0] and "expected one of escalate, retry, fail" in errs[0]
