"""Every ```yaml block in docs/ (and the READMEs) is checked, so the docs
cannot drift from the code again:

- a behaviour tree (a mapping with ``root``) loads with the real node
  registry, as a file in ``trees/`` (so ``common/...`` are the shipped
  sub-trees), and fits the JSON Schema ``rll-bt tree schema`` writes;
- a robot configuration (``base``) passes ``robot_config.schema.json``;
- a camera file of the vision commands (``fx``) loads with their loader;
- anything else (the real refbox's configuration, with its tags) at least
  parses as YAML.

A ``$schema=`` path in a block must name a file that exists.  Python
blocks of docs/trees.md must at least compile.
"""
from __future__ import annotations

import ast
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

import jsonschema
import pytest
import yaml

from rll_bt.tree import TreeLoadError, parse_tree
from rll_bt.tree.schemagen import tree_schema
from tests.support import REPO, TREES

DOCS = sorted((REPO / "docs").rglob("*.md")) + [REPO / "README.md", TREES / "README.md"]
_FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[A-Za-z0-9_+-]*)[^\n]*$")


@dataclass
class Block:
    doc: Path
    line: int            # 1-based line of the first line inside the fence
    lang: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(REPO).as_posix()}:{self.line}"


def blocks(path: Path) -> list[Block]:
    """The fenced code blocks of a Markdown file, dedented by their fence's indentation."""
    out: list[Block] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, lang = m.group("indent"), m.group("lang").lower()
        end = next((j for j in range(i + 1, len(lines))
                    if lines[j].strip() == "```" and len(lines[j]) - len(lines[j].lstrip()) <= len(indent)),
                   None)
        assert end is not None, f"{path}:{i + 1}: a code block that never ends"
        body = "\n".join(ln[len(indent):] if ln.startswith(indent) else ln for ln in lines[i + 1:end])
        out.append(Block(path, i + 2, lang, textwrap.dedent(body) + "\n"))
        i = end + 1
    return out


ALL = [b for d in DOCS for b in blocks(d)]
YAML_BLOCKS = [b for b in ALL if b.lang in ("yaml", "yml")]


def kind(block: Block) -> str:
    try:
        data = yaml.safe_load(block.text)
    except yaml.YAMLError:
        return "other"          # tags of another program: parsed without them below
    if isinstance(data, dict) and "root" in data:
        return "tree"
    if isinstance(data, dict) and "base" in data:
        return "robot_config"
    if isinstance(data, dict) and "fx" in data:
        return "camera_calibration"
    return "other"


@pytest.fixture(scope="module")
def schema():
    return tree_schema()


@pytest.mark.parametrize("block", YAML_BLOCKS, ids=lambda b: b.where)
def test_yaml_block(block, schema, tmp_path):
    for ref in re.findall(r"\$schema=(\S+)", block.text):
        if not ref.startswith("<"):
            assert (block.doc.parent / ref).resolve().is_file(), f"{block.where}: $schema={ref} names no file"
    k = kind(block)
    if k == "tree":
        try:
            parse_tree(TREES / "docs_example.yaml", text=block.text, search_path=[TREES])
        except TreeLoadError as exc:
            pytest.fail(f"{block.where}: the tree does not load:\n{exc}")
        errors = [f"{'/'.join(map(str, e.absolute_path))}: {e.message[:200]}"
                  for e in jsonschema.Draft202012Validator(schema).iter_errors(yaml.safe_load(block.text))]
        assert errors == [], f"{block.where}: the tree does not fit the JSON Schema"
    elif k == "robot_config":
        from backends.robotino.config import parse_robot_config
        parse_robot_config(yaml.safe_load(block.text), block.doc)
    elif k == "camera_calibration":
        from skills.perception.camera_file import load_camera
        f = tmp_path / "camera.yaml"
        f.write_text(block.text)
        load_camera(f)
    else:
        nodes = list(yaml.compose_all(block.text, Loader=yaml.SafeLoader))   # tags kept, not constructed
        assert nodes, f"{block.where}: an empty YAML block"


def test_the_docs_have_yaml_blocks_of_every_kind():
    """The test above has something to check: docs/trees.md is all trees, and the
    other kinds appear where the hardware and perception pages show them."""
    kinds = {}
    for b in YAML_BLOCKS:
        kinds.setdefault(b.doc.relative_to(REPO).as_posix(), []).append(kind(b))
    assert len(kinds["docs/trees.md"]) >= 6 and set(kinds["docs/trees.md"]) == {"tree"}
    every = {k for ks in kinds.values() for k in ks}
    assert {"tree", "robot_config", "camera_calibration", "other"} <= every


def test_the_shipped_trees_fit_the_json_schema(schema):
    validator = jsonschema.Draft202012Validator(schema)
    for path in sorted(TREES.rglob("*.yaml")):
        errors = [e.message[:200] for e in validator.iter_errors(yaml.safe_load(path.read_text()))]
        assert errors == [], path


@pytest.mark.parametrize("block", [b for b in ALL if b.lang == "python" and b.doc.name == "trees.md"],
                         ids=lambda b: b.where)
def test_python_blocks_of_the_tree_page_compile(block):
    ast.parse(block.text, filename=block.where)


def test_a_drifted_block_fails(tmp_path, schema):
    """The check is real: the old first example of docs/trees.md (ports, files and
    node types that do not exist) does not load."""
    old = textwrap.dedent("""\
        task:
          station: {type: str}
        root:
          recovery:
            action:
              sequence_with_memory:
                - approach_station: {station: $task.station, side: output}
            recoveries:
              - subtree: {file: common/realign.yaml, params: {station: $task.station}}
        """)
    with pytest.raises(TreeLoadError) as exc:
        parse_tree(TREES / "docs_example.yaml", text=old, search_path=[TREES])
    text = str(exc.value)
    assert "unknown port 'station' for node type 'approach_station'" in text
    assert "has no parameter 'station'" in text
