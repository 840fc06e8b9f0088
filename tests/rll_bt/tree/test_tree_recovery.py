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
