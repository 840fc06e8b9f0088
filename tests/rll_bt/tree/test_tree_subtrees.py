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


LEAF = """
    params:
      machine: {type: str}
      side: {type: str, default: INPUT, choices: [INPUT, OUTPUT]}
      slot: {type: int, default: 0}
    root:
      reactive_sequence:
        - set_blackboard: {key: $bb./got/machine, value: $param.machine}
        - set_blackboard: {key: $bb./got/side, value: $param.side}
        - set_blackboard: {key: $bb./got/slot, value: $param.slot}
    """


def _got(tree):
    assert tree.tick() is Status.SUCCESS
    return {k: tree.blackboard.get(f"/got/{k}") for k in ("machine", "side", "slot")}


def test_pass_names_parameters_and_task_fields_through(make):
    """`pass: [...]` is short for `params: {x: $param.x}` (or `$task.x` when
    the caller has no parameter x): both load to the same bindings."""
    short = """
        task:
          machine: {type: str}
        params:
          side: {type: str, default: OUTPUT}
        root:
          subtree: {file: leaf.yaml, pass: [machine, side]}
        """
    long = """
        task:
          machine: {type: str}
        params:
          side: {type: str, default: OUTPUT}
        root:
          subtree: {file: leaf.yaml, params: {machine: $task.machine, side: $param.side}}
        """
    a, _ = make(short, task={"machine": "C-BS"}, files={"leaf.yaml": LEAF})
    b, _ = make(long, task={"machine": "C-BS"}, files={"leaf.yaml": LEAF}, name="long.yaml")
    assert _got(a) == _got(b) == {"machine": "C-BS", "side": "OUTPUT", "slot": 0}
    sub_a, sub_b = a.spec.root, b.spec.root
    assert {k: v.source for k, v in sub_a.slots["root"][0].slots["children"][0].ports.items()} == \
        {k: v.source for k, v in sub_b.slots["root"][0].slots["children"][0].ports.items()}


def test_pass_all_passes_what_the_caller_has_and_params_stay(make):
    tree, _ = make("""
        task:
          machine: {type: str}
          slot: {type: int, default: 2}
        root:
          subtree: {file: leaf.yaml, pass: all, params: {machine: C-RS1}}
        """, task={"machine": "C-BS"}, files={"leaf.yaml": LEAF})
    # machine given explicitly wins, slot passed from the task, side (the caller has none) its default
    assert _got(tree) == {"machine": "C-RS1", "side": "INPUT", "slot": 2}


def test_pass_errors_name_the_place(check):
    files = {"leaf.yaml": LEAF}
    errs = check("task: {machine: str}\nroot:\n  subtree: {file: leaf.yaml, pass: [machine, sidee]}\n", files=files)
    assert any("tree.yaml:3:46: cannot pass 'sidee'" in e for e in errs), errs
    errs = check("params: {machine: str, colour: str}\nroot:\n  subtree: {file: leaf.yaml, pass: [machine, colour]}\n",
                 files=files)
    assert any("tree.yaml:3:46:" in e and "has no parameter 'colour'" in e for e in errs), errs
    errs = check("params: {machine: str}\nroot:\n  subtree: {file: leaf.yaml, pass: [machine], "
                 "params: {machine: x}}\n", files=files)
    assert any("tree.yaml:3:37: parameter 'machine' is both passed and given" in e for e in errs), errs
    errs = check("root:\n  subtree: {file: leaf.yaml, pass: yes}\n", files=files)
    assert "tree.yaml:2:36: `pass` takes a list of parameter names or `all`" in errs[0]
    errs = check("params: {side: str}\nroot:\n  subtree: {file: leaf.yaml, pass: all}\n", files=files)
    assert "requires parameter 'machine'" in errs[0] and "pass: [machine]" in errs[0]
    errs = check("params: {machine: int}\nroot:\n  subtree: {file: leaf.yaml, pass: [machine]}\n", files=files)
    assert "expects str but $param.machine is int" in errs[0]


SEARCH = """
    params:
      zone: {type: int}
    outputs:
      found: {type: list, doc: names of the stations seen}
      count: {type: int, doc: how many}
    root:
      reactive_sequence:
        - set_blackboard: {key: $bb.found, value: [C-BS, C-CS1]}
        - set_blackboard: {key: $bb.count, value: 2}
        - set_blackboard: {key: $bb.scratch, value: $param.zone}
    """


def test_declared_outputs_are_the_callers_keys_of_the_same_name(make):
    tree, _ = make("""
        outputs:
          found: {type: list, doc: what the search found}
        root:
          sequence_with_memory:
            - subtree: {file: search.yaml, params: {zone: 3}, remap: {count: $bb.seen}}
            - check_blackboard: {condition: "seen == 2"}
        """, files={"search.yaml": SEARCH})
    assert tree.tick() is Status.SUCCESS
    bb = tree.blackboard
    assert bb.get("/found") == ["C-BS", "C-CS1"]          # an output: the caller's key
    assert bb.get("/seen") == 2 and "/count" not in bb     # remap sends an output elsewhere
    assert bb.get("/search/scratch") == 3                  # not an output: the subtree's own scope
    assert tree.outputs() == {"found": ["C-BS", "C-CS1"]}  # what the caller of the root tree reads
    assert tree.spec.output_keys == {"found": "/found"} and tree.spec.outputs["found"].ptype.name == "list"


def test_an_output_nothing_writes_is_an_error(check):
    errs = check("outputs:\n  found: {type: list}\nroot:\n  set_blackboard: {key: $bb.fonud, value: []}\n")
    assert len(errs) == 1 and "tree.yaml:2:3: output 'found' is declared but nothing in" in errs[0]
    errs = check("outputs:\n  found: {type: list, default: []}\nroot:\n  set_blackboard: {key: $bb.found, value: []}\n")
    assert "tree.yaml:2:32: output 'found' takes no default" in errs[0]
    errs = check("outputs:\n  n: int\nroot:\n  set_blackboard: {key: $bb.n, value: many}\n")
    assert "writes str to /n, which output 'n' of" in errs[0]


def test_a_key_read_that_nothing_writes_or_declares_is_an_error(check):
    errs = check("""
        root:
          sequence_with_memory:
            - set_blackboard: {key: $bb.done, value: true}
            - check_blackboard: {condition: "dnoe == true"}
        """)
    assert len(errs) == 1
    assert "tree.yaml:5:37: port 'condition' of 'check_blackboard' reads blackboard key /dnoe, which nothing" in errs[0]
    assert "did you mean '/done'?" in errs[0]
    # declared under blackboard: (written from outside), the engine's error keys, a subtree's output: all fine
    assert check("""
        blackboard:
          phase: str
        root:
          sequence_with_memory:
            - subtree: {file: search.yaml, params: {zone: 1}}
            - check_blackboard: {condition: "phase == 'PRODUCTION' and /error/code == null and count > 0"}
        """, files={"search.yaml": SEARCH}) == []
    # a subtree's own key is not the caller's
    errs = check("root:\n  sequence_with_memory:\n    - subtree: {file: search.yaml, params: {zone: 1}}\n"
                 "    - check_blackboard: {condition: \"scratch == 1\"}\n", files={"search.yaml": SEARCH})
    assert "reads blackboard key /scratch, which nothing" in errs[0]
