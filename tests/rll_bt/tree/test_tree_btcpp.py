"""Trees to BehaviorTree.CPP v4 XML and back (``rll-bt tree export|import``).

Every shipped tree goes YAML -> XML -> YAML and must load to the same tree:
the same node types, names, ports (literal values, blackboard keys, task
fields and parameters), children in the same slots, the same subtree
instances and blackboard scopes, the same declarations.  The XML must pass
the checks BT.CPP 4's parser makes (:mod:`rll_bt.tree.btcpp.verify`).
"""
from __future__ import annotations

import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from rll_bt.cli import main
from rll_bt.tree import TreeLoadError, parse_tree
from rll_bt.tree.btcpp import export_xml, import_xml, nodes_model, problems, write_trees
from rll_bt.tree.btcpp.mapping import text_to_value, value_to_text
from rll_bt.tree.ports import Key, Unknown
from tests.support import TREES

SHIPPED = sorted(TREES.glob("*.yaml")) + sorted(p for p in TREES.rglob("*.yaml") if p.parent != TREES)
DATA = Path(__file__).parent / "data"


def _binding(b):
    if isinstance(b, Key):
        return ("key", b.key)
    if isinstance(b, Unknown):
        return ("unknown", b.source, b.ptype.name)
    value = getattr(b.value, "source", b.value)          # a condition: its text
    return ("const", type(value).__name__, value)


def meaning(spec, base: Path) -> tuple:
    """Everything a loaded tree means, with file names relative to ``base``."""
    def rel(f):
        return None if f is None else Path(f).resolve().relative_to(base.resolve()).as_posix()

    def node(n):
        return (n.type, n.name, n.kind, n.scope, rel(n.file),
                tuple(sorted((k, _binding(b)) for k, b in n.ports.items())),
                tuple((s, tuple(node(c) for c in kids)) for s, kids in sorted(n.slots.items())))

    return (spec.name, spec.doc.strip(), node(spec.root),
            tuple(sorted((k, tuple(sorted(d.describe().items()))) for k, d in spec.task.items())),
            tuple(sorted((k, repr(sorted(d.describe().items()))) for k, d in spec.params.items())),
            tuple(sorted((k, repr(sorted(d.describe().items())), spec.output_keys[k])
                         for k, d in spec.outputs.items())),
            tuple(sorted(spec.blackboard_init.items())),
            tuple(sorted((k, t.name) for k, t in spec.key_types.items())),
            tuple(sorted(rel(f) for f in spec.files)))


def roundtrip(path: Path, tmp: Path, search=()) -> tuple[str, Path]:
    xml = export_xml([path], search_path=search)
    files = import_xml(xml)
    write_trees(files, tmp)
    return xml, tmp / next(iter(files))


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.relative_to(TREES).as_posix())
def test_every_shipped_tree_round_trips(path, tmp_path):
    xml, back = roundtrip(path, tmp_path, search=[TREES])
    assert problems(xml) == []
    assert back == tmp_path / path.name           # paths are kept relative to the root file's folder
    before = parse_tree(path, search_path=[TREES])
    after = parse_tree(back)
    assert meaning(after, tmp_path) == meaning(before, path.parent)
    # and a second trip writes the same XML
    assert export_xml([back]).replace(' _file="', "") == xml.replace(' _file="', "")


def test_the_shipped_trees_are_all_there():
    """SHIPPED finds every tree of the package (task trees and the subtrees in every folder)."""
    names = {p.relative_to(TREES).as_posix() for p in SHIPPED}
    assert len(SHIPPED) == len(names) >= 19
    assert {"deliver.yaml", "explore_zone.yaml", "common/grab_at.yaml"} <= names


def test_all_task_trees_in_one_document(tmp_path):
    roots = sorted(TREES.glob("*.yaml"))
    xml = export_xml(roots, search_path=[TREES])
    assert problems(xml) == []
    doc = ET.fromstring(xml)
    ids = [t.get("ID") for t in doc.findall("BehaviorTree")]
    assert len(ids) == len(SHIPPED) and len(set(ids)) == len(ids)
    assert doc.get("main_tree_to_execute") == ids[0] and doc.get("BTCPP_format") == "4"
    # a tree that shares its name with a node type gets another ID (BT.CPP refuses the clash)
    files = import_xml(xml)
    assert set(files) == {p.relative_to(TREES).as_posix() for p in SHIPPED}
    write_trees(files, tmp_path)
    for r in roots:
        assert meaning(parse_tree(tmp_path / r.name), tmp_path) == meaning(parse_tree(r), TREES)


def test_what_groot_sees(tmp_path):
    """Built-ins where the meaning is the same, rll-bt types declared in the model,
    SubTree with its ports remapped, parameters as the subtree model's ports."""
    xml = export_xml([TREES / "common" / "grab_at.yaml"])
    doc = ET.fromstring(xml)
    main = doc.find("BehaviorTree")
    assert main.get("ID") == "GrabAt" and main.get("_file") == "grab_at.yaml"
    seq = main[0]
    assert seq.tag == "Sequence"
    sub = seq[0]
    assert sub.tag == "SubTree" and sub.get("ID") == "Approach"
    # `pass: all`: the values BT.CPP reads, and the short form (an attribute BT.CPP skips) for the way back
    assert sub.attrib == {"ID": "Approach", "machine": "{machine}", "side": "{side}", "shelf_slot": "{shelf_slot}",
                          "_pass": "all"}
    rec = seq[1]
    assert rec.tag == "recovery" and [c.tag for c in rec] == ["Sequence", "SubTree", "SubTree"]
    assert [c.get("ID") for c in rec[1:]] == ["Realign", "Reapproach"]     # shared recovery sub-trees
    assert rec.get("on_recovery_failure") == "retry"              # the policy is a port of the Control
    model = doc.find("TreeNodesModel")
    kinds = {el.get("ID"): el.tag for el in model}
    assert kinds["recovery"] == "Control" and kinds["grab"] == "Action"
    assert kinds["holding_workpiece"] == "Condition" and kinds["GrabAt"] == "SubTree"
    assert "Sequence" not in kinds and "sequence_with_memory" not in kinds
    approach = model.find("SubTree[@ID='Approach']")
    ports = {p.get("name"): p for p in approach}
    assert set(ports) == {"machine", "side", "shelf_slot"}
    assert ports["shelf_slot"].get("default") == "0" and ports["shelf_slot"].get("type") == "int"
    grab = model.find("Action[@ID='grab']")
    assert {p.get("name"): p.tag for p in grab if p.tag.endswith("_port")}["holding"] == "output_port"
    # the instance named in YAML keeps its name; its scope is the same after the trip
    assert doc.find("BehaviorTree[@ID='Reapproach']//SubTree[@name='approach_again']") is not None


def test_pass_goes_to_xml_and_back_as_the_short_form(tmp_path):
    xml = export_xml([TREES / "retrieve_cap.yaml"], search_path=[TREES])
    doc = ET.fromstring(xml)
    grab = doc.find(".//SubTree[@ID='GrabAt']")
    assert grab.attrib == {"ID": "GrabAt", "side": "SHELF", "machine": "{@task.machine}",
                           "shelf_slot": "{@task.shelf_slot}", "_pass": "machine shelf_slot"}
    files = import_xml(xml)
    assert "subtree: {file: common/grab_at.yaml" not in files["retrieve_cap.yaml"]     # block style, but:
    back = yaml.safe_load(files["retrieve_cap.yaml"])
    seq = back["root"]["selector_with_memory"]["children"][1]["sequence_with_memory"]["children"]
    sub = seq[1]["selector_with_memory"]["children"][1]["subtree"]
    assert sub == {"file": "common/grab_at.yaml", "pass": ["machine", "shelf_slot"], "params": {"side": "SHELF"}}
    # edited in Groot: a passed value changed by hand becomes an explicit parameter
    edited = xml.replace('shelf_slot="{@task.shelf_slot}"', 'shelf_slot="2"', 1)
    back = yaml.safe_load(import_xml(edited)["retrieve_cap.yaml"])
    seq = back["root"]["selector_with_memory"]["children"][1]["sequence_with_memory"]["children"]
    sub = seq[1]["selector_with_memory"]["children"][1]["subtree"]
    assert sub["pass"] == ["machine"] and sub["params"] == {"side": "SHELF", "shelf_slot": 2}
    # BT.CPP 4.10's short form {=}: the caller's entry of the same name
    hand = xml.replace('<SubTree ID="Approach" machine="{machine}" side="{side}" shelf_slot="{shelf_slot}" '
                       '_pass="all" />', '<SubTree ID="Approach" machine="{=}" side="{side}" shelf_slot="{=}" />')
    assert hand != xml
    back = yaml.safe_load(import_xml(hand)["common/grab_at.yaml"])
    assert back["root"]["sequence_with_memory"]["children"][0]["subtree"]["params"] == \
        {"machine": "$param.machine", "side": "$param.side", "shelf_slot": "$param.shelf_slot"}


SAMPLE = textwrap.dedent("""\
    name: sample
    doc: every construct the export has to carry
    task:
      zone: {type: str, doc: "a zone"}
      limit: {type: int, default: 3}
    params:
      speed: {type: float, default: 0.5, doc: "m/s"}
      mode: {type: str, choices: [fast, slow], required: false}
    blackboard:
      count: {type: int, default: 0}
      /shared/flag: {type: bool, default: false}
    root:
      parallel:
        name: both
        policy: selected
        synchronise: true
        selected: [worker]
        children:
          - retry:
              name: worker
              attempts: 3
              delay: 0.5
              backoff: 2.0
              attempt: $bb.attempt
              child:
                timeout:
                  seconds: 2.5
                  child: {wait: {seconds: 0.0015}}
              on_retry: {log: {message: "$$not a reference"}}
          - retry: {attempts: $task.limit, child: {repeat: {count: 2, child: success}}}
          - guard:
              condition: holding_flag
              when_false: success
              child: {timeout: {seconds: 1, error_code: TIMEOUT, child: running}}
          - guard:
              condition: "count < $task.limit and /shared/flag == false"
              child:
                one_shot:
                  policy: on_completion
                  child:
                    sequence_with_memory:
                      - set_blackboard: {key: $bb.count, value: 1}
                      - set_blackboard: {key: $bb.text, value: "true"}
                      - set_blackboard: {key: $bb./shared/flag, value: true}
                      - set_blackboard: {key: $bb.pose, value: {x: $param.speed, y: 0.5}}
                      - set_blackboard: {key: $bb.empty, value: ""}
                      - log: {message: $task.zone, value: $bb.count, level: debug}
          - subtree: {file: sub/leaf.yaml, name: first, params: {gain: $param.speed}, pass: [mode],
                      remap: {out: $bb.result, done: $bb.first_done}}
          - subtree: {file: sub/leaf.yaml, autoremap: true, pass: all}
          - recovery:
              on_recovery_failure: fail
              retries: 2
              action: failure
              recoveries: [success, {check_blackboard: {condition: "first_done and done"}}]
          - reactive_selector: [failure, {inverter: {child: {force_failure: {child: success}}}}]
    """)
LEAF = textwrap.dedent("""\
    params:
      gain: {type: float, default: 1.0}
      mode: {type: str, default: fast}
    outputs:
      done: {type: bool, doc: "the leaf ran"}
    root:
      reactive_sequence:
        - check_blackboard: {condition: "$param.gain > 0.1"}
        - set_blackboard: {key: $bb.out, value: $param.gain}
        - set_blackboard: {key: $bb.done, value: true}
    """)


def _write_sample(src: Path) -> Path:
    (src / "sub").mkdir(parents=True)
    (src / "sample.yaml").write_text(SAMPLE)
    (src / "sub" / "leaf.yaml").write_text(LEAF)
    return src / "sample.yaml"


@pytest.fixture
def registry():
    from rll_bt.tree import Node, Status, default_registry

    reg = default_registry().child()

    class HoldingFlag(Node):
        """Test condition: always SUCCESS."""
        kind = "condition"

        def update(self):
            return Status.SUCCESS
    reg.register(HoldingFlag, "holding_flag")
    return reg


def test_every_construct_round_trips(tmp_path, registry):
    src = _write_sample(tmp_path / "src")
    xml = export_xml([src], registry=registry)
    assert problems(xml) == []
    doc = ET.fromstring(xml)
    tags = [el.tag for el in doc.iter()]
    assert "Timeout" in tags and "RetryUntilSuccessful" in tags and "Repeat" in tags
    assert doc.find(".//Timeout").get("msec") == "2500"
    assert doc.find(".//RetryUntilSuccessful").get("num_attempts") == "{@task.limit}"
    assert doc.find(".//wait").get("seconds") == "0.0015"          # not a whole number of ms: stays wait
    assert doc.find(".//timeout").get("error_code") == "TIMEOUT"   # a port Timeout has not: stays timeout
    assert doc.find(".//set_blackboard[@key='{@shared/flag}']") is not None
    assert doc.find(".//set_blackboard[@key='{text}']").get("value") == 'json:"true"'
    assert doc.find(".//SubTree[@name='first']").get("out") == "{result}"
    assert doc.find(".//SubTree[@_autoremap='true']") is not None
    first = doc.find(".//SubTree[@name='first']")
    assert first.get("done") == "{first_done}" and first.get("mode") == "{mode}" and first.get("_pass") == "mode"
    assert doc.find(".//SubTree[@_autoremap='true']").get("done") == "{done}"     # an output: same name
    leaf_model = {pt.get("name"): pt.tag for pt in doc.find("TreeNodesModel/SubTree[@ID='Leaf']")}
    assert leaf_model == {"gain": "input_port", "mode": "input_port", "done": "output_port"}
    assert doc.find(".//recovery").get("on_recovery_failure") == "fail"
    files = import_xml(xml, registry=registry)
    assert set(files) == {"sample.yaml", "sub/leaf.yaml"}
    out = tmp_path / "out"
    write_trees(files, out)
    before = parse_tree(src, registry=registry)
    after = parse_tree(out / "sample.yaml", registry=registry)
    assert meaning(after, out) == meaning(before, src.parent)
    with pytest.raises(FileExistsError):
        write_trees(files, out)


def test_a_value_bt_cpp_cannot_hold_is_refused(tmp_path):
    (tmp_path / "t.yaml").write_text("root:\n  log: {message: '{looks_like_a_key}'}\n")
    with pytest.raises(TreeLoadError) as exc:
        export_xml([tmp_path / "t.yaml"])
    assert "t.yaml:2:" in str(exc.value) and "blackboard reference" in str(exc.value)


@settings(max_examples=150, deadline=None)
@given(st.one_of(st.text(max_size=12), st.integers(), st.floats(allow_nan=False, allow_infinity=False),
                 st.booleans(), st.lists(st.integers(), max_size=3),
                 st.dictionaries(st.text(max_size=3), st.text(max_size=3), max_size=2)),
       st.sampled_from(["any", "str", "int", "float", "bool", "list", "dict"]))
def test_literal_values_survive(value, ptype):
    if ptype == "str" and not isinstance(value, str):
        return
    if isinstance(value, str) and (value.startswith("$") or (value.startswith("{") and value.endswith("}"))):
        return
    assert text_to_value(value_to_text(value, ptype), ptype, set()) == value


def test_references():
    assert value_to_text("$bb.goal", "pose") == "{goal}"
    assert value_to_text("$bb./game/phase", "str") == "{@game/phase}"
    assert value_to_text("$task.zone", "str") == "{@task.zone}"
    assert value_to_text("$param.side", "str") == "{side}"
    assert value_to_text("$$5", "str") == "$5"
    assert text_to_value("{side}", "str", {"side"}) == "$param.side"
    assert text_to_value("{side}", "str", set()) == "$bb.side"
    assert text_to_value("{@task.zone}", "str", set()) == "$task.zone"
    assert text_to_value("$5", "str", set()) == "$$5"
    assert text_to_value("1;2;3", "list[int]", set()) == [1, 2, 3]      # BT.CPP's own list spelling


def test_bt_cpp_file_written_by_hand(tmp_path):
    """A file in BT.CPP's own style: explicit <Action ID=..>, built-ins, no _file."""
    xml = textwrap.dedent("""\
        <root BTCPP_format="4" main_tree_to_execute="MainTree">
          <BehaviorTree ID="MainTree">
            <ReactiveFallback name="top">
              <Action ID="log" message="hello"/>
              <RetryUntilSuccessful num_attempts="2">
                <SubTree ID="GoThere" target="C_Z11"/>
              </RetryUntilSuccessful>
              <Sleep msec="1500"/>
            </ReactiveFallback>
          </BehaviorTree>
          <BehaviorTree ID="GoThere">
            <navigate_to_zone zone="{target}"/>
          </BehaviorTree>
          <TreeNodesModel>
            <SubTree ID="GoThere"><input_port name="target" type="std::string"/></SubTree>
          </TreeNodesModel>
        </root>""")
    files = import_xml(xml)
    assert list(files) == ["main_tree.yaml", "go_there.yaml"]
    write_trees(files, tmp_path)
    spec = parse_tree(tmp_path / "main_tree.yaml")
    kinds = [(d, n.type) for d, n in spec.root.walk()]
    assert kinds == [(0, "reactive_selector"), (1, "log"), (1, "retry"), (2, "subtree"), (3, "navigate_to_zone"),
                     (1, "wait")]
    wait = next(n for _, n in spec.root.walk() if n.type == "wait")
    assert wait.const("seconds") == 1.5
    nav = next(n for _, n in spec.root.walk() if n.type == "navigate_to_zone")
    assert nav.ports["zone"].value == "C_Z11"


@pytest.mark.parametrize("xml, message", [
    ("<root BTCPP_format='4'><BehaviorTree ID='A'><nope/></BehaviorTree></root>", "unknown node type 'nope'"),
    ("<root BTCPP_format='4'><BehaviorTree ID='A'><Sequence><log mesage='x'/></Sequence></BehaviorTree></root>",
     "unknown port 'mesage'"),
    ("<root BTCPP_format='4'><BehaviorTree ID='A'><SubTree ID='B'/></BehaviorTree></root>",
     "no <BehaviorTree> with that ID"),
    ("<root BTCPP_format='4'><BehaviorTree ID='A'><Parallel><success/></Parallel></BehaviorTree></root>",
     "without an rll-bt equivalent"),
    ("<root><BehaviorTree ID='A'>", "not well-formed XML"),
    ("<!DOCTYPE r [<!ENTITY a 'aaaa'>]><root/>", "refused XML"),
    ("<trees/>", "not <root>"),
])
def test_bad_xml_is_reported_with_a_line(xml, message):
    with pytest.raises(TreeLoadError) as exc:
        import_xml(xml, "in.xml")
    assert message in str(exc.value) and "in.xml:" in str(exc.value)


@pytest.mark.parametrize("edit, message", [
    (lambda x: x.replace('BTCPP_format="4"', 'BTCPP_format="3"'), 'BTCPP_format="4"'),
    (lambda x: x.replace('<SubTree ID="Approach"', '<SubTree ID="Nowhere"', 1), "no <BehaviorTree> with that ID"),
    (lambda x: x.replace('distance="0.2"', 'distanse="0.2"'), "a port with name [distanse]"),
    (lambda x: x.replace('<Action ID="back_off">', '<Action ID="back_of">'), "node not recognized: back_off"),
    (lambda x: x.replace('main_tree_to_execute="GrabAt"', 'main_tree_to_execute="Nope"'), "names no"),
    (lambda x: x.replace("<holding_workpiece />", "<Inverter><holding_workpiece /><AlwaysSuccess/></Inverter>", 1),
     "exactly 1 child"),
    (lambda x: x.replace("<holding_workpiece />", "<holding_workpiece><AlwaysSuccess/></holding_workpiece>", 1),
     "must not have any child"),
])
def test_the_checker_finds_what_bt_cpp_refuses(edit, message):
    xml = export_xml([TREES / "common" / "grab_at.yaml"])
    assert problems(xml) == []
    found = problems(edit(xml))
    assert any(message in p for p in found), found


def test_catalogue_is_a_tree_nodes_model():
    doc = ET.fromstring(nodes_model())
    assert doc.tag == "root" and doc.get("BTCPP_format") == "4"
    model = doc.find("TreeNodesModel")
    kinds = {el.get("ID"): el.tag for el in model}
    for name, kind in (("grab", "Action"), ("localised", "Condition"), ("recovery", "Control"),
                       ("timeout", "Decorator"), ("retry", "Control"), ("parallel", "Control")):
        assert kinds[name] == kind
    assert "subtree" not in kinds and "sequence_with_memory" not in kinds    # BT.CPP's own Sequence
    ports = {p.get("name"): p for p in model.find("Action[@ID='approach_station']")
             if p.tag.endswith("_port")}
    assert ports["side"].get("default") == "OUTPUT" and ports["machine"].text
    assert problems(nodes_model().replace("</TreeNodesModel>", "</TreeNodesModel><BehaviorTree ID='T'>"
                                          "<recovery><grab machine='C-BS'/><back_off/></recovery>"
                                          "</BehaviorTree>")) == []


def test_cli(tmp_path, capsys):
    out = tmp_path / "t.xml"
    assert main(["tree", "export", "--format", "btcpp", str(TREES / "deliver.yaml"), "-o", str(out)]) == 0
    assert problems(out.read_text()) == []
    assert main(["tree", "import", str(out), "-o", str(tmp_path / "y")]) == 0
    assert (tmp_path / "y" / "common" / "put_at.yaml").is_file()
    assert main(["tree", "import", str(out), "-o", str(tmp_path / "y")]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["tree", "import", str(out), "-o", str(tmp_path / "y"), "--force"]) == 0
    assert main(["tree", "export", str(tmp_path / "missing.yaml")]) == 2
    assert main(["tree", "export", str(DATA / "bad.yaml")]) == 2
    bad = tmp_path / "bad.xml"
    bad.write_text("<root BTCPP_format='4'><BehaviorTree ID='A'><wiat/></BehaviorTree></root>")
    assert main(["tree", "import", str(bad), "-o", str(tmp_path / "z")]) == 2
    assert "bad.xml:1:" in capsys.readouterr().err
    assert main(["tree", "nodes", "--btcpp"]) == 0
    assert "<TreeNodesModel>" in capsys.readouterr().out
    assert main(["tree", "export", str(TREES / "go_to.yaml")]) == 0
    assert capsys.readouterr().out.startswith('<?xml version="1.0"')
