"""Subtrees by file: parameters, scoped blackboards, remapping, cycles."""
import re

from rll_bt.tree import Status

SUB = """
    name: fetch
    params:
      station: {type: str, doc: where to fetch from}
      tries: {type: int, default: 2}
    blackboard:
      count: {type: int, default: 0}
    root:
      reactive_sequence:
        - set_blackboard: {key: $bb.result, value: $param.station}
        - set_blackboard: {key: $bb.tries_used, value: $param.tries}
        - set_blackboard: {key: $bb./shared/last, value: $param.station}
    """


def test_instances_are_isolated_and_remapped(make):
    tree, _ = make("""
        root:
          sequence_with_memory:
            - subtree: {file: sub/fetch.yaml, name: a, params: {station: BS}}
            - subtree: {file: sub/fetch.yaml, name: b, params: {station: CS1, tries: 5},
                        remap: {result: $bb.b_out}}
            - subtree: {file: sub/fetch.yaml, params: {station: RS1}}
            - subtree: {file: sub/fetch.yaml, params: {station: RS2}}
        """, files={"sub/fetch.yaml": SUB})
    assert tree.tick() is Status.SUCCESS
    bb = tree.blackboard
    assert bb.get("/a/result") == "BS" and bb.get("/a/tries_used") == 2
    assert bb.get("/b_out") == "CS1" and "/b/result" not in bb and bb.get("/b/tries_used") == 5
    assert bb.get("/fetch/result") == "RS1" and bb.get("/fetch_2/result") == "RS2"   # implicit names
    assert bb.get("/a/count") == 0 and bb.get("/b/count") == 0                       # declared per instance
    assert bb.get("/shared/last") == "RS2"                                            # absolute keys are shared


def test_autoremap_and_blackboard_params(make):
    tree, _ = make("""
        root:
          sequence_with_memory:
            - set_blackboard: {key: $bb.goal, value: M_Z42}
            - subtree: {file: copy.yaml, autoremap: true, params: {src: $bb.goal}}
        """, files={"copy.yaml": """
        params:
          src: {type: str}
        root:
          set_blackboard: {key: $bb.copied, value: $param.src}
        """})
    assert tree.tick() is Status.SUCCESS
    assert tree.blackboard.get("/copied") == "M_Z42"


def test_nested_subtrees_scope(make):
    tree, _ = make("root:\n  subtree: {file: outer.yaml}\n", files={
        "outer.yaml": "root:\n  subtree: {file: inner.yaml, name: deep}\n",
        "inner.yaml": "root:\n  set_blackboard: {key: $bb.x, value: 1}\n"})
    tree.tick()
    assert tree.blackboard.snapshot() == {"/outer/deep/x": 1}


def test_subtree_cycle_missing_file_and_bad_params(check):
    errs = check("root:\n  subtree: {file: a.yaml}\n", files={
        "a.yaml": "root:\n  subtree: {file: b.yaml}\n",
        "b.yaml": "root:\n  reactive_sequence:\n    - success\n    - subtree: {file: a.yaml}\n"})
    assert len(errs) == 1
    assert re.search(r"b\.yaml:4:23: subtree cycle: \S*a\.yaml -> \S*b\.yaml -> \S*a\.yaml", errs[0])
    errs = check("root:\n  subtree: {file: fetchh.yaml}\n", files={"fetch.yaml": SUB})
    assert "tree.yaml:2:19: subtree file 'fetchh.yaml' not found" in errs[0] and "fetch.yaml" in errs[0]
    errs = check("root:\n  subtree: {file: fetch.yaml, params: {statoin: BS}}\n", files={"fetch.yaml": SUB})
    assert any("has no parameter 'statoin'" in e and "did you mean 'station'" in e for e in errs)
    assert any("requires parameter 'station'" in e for e in errs)
    errs = check("root:\n  subtree: {file: fetch.yaml, params: {station: 3}}\n", files={"fetch.yaml": SUB})
    assert "expected str, got int 3" in errs[0]
    errs = check("""
        root:
          reactive_sequence:
            - subtree: {file: fetch.yaml, name: x, params: {station: BS}}
            - subtree: {file: fetch.yaml, name: x, params: {station: BS}}
        """, files={"fetch.yaml": SUB})
    assert "two subtree instances named 'x'" in errs[0]


def test_errors_inside_subtree_name_the_subtree_file(check):
    errs = check("root:\n  subtree: {file: bad.yaml}\n", files={"bad.yaml": "root:\n  wiat: {seconds: 1}\n"})
    assert len(errs) == 1 and "bad.yaml:2:3: unknown node type 'wiat'" in errs[0]
    assert "did you mean 'wait'" in errs[0]
