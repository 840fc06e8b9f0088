"""Every file in ``trees/`` validates, there is a tree for every task kind
of the team protocol, and each tree takes exactly the task fields the
agent gives it."""
from __future__ import annotations

import pytest

from rll_bt import msgs, rules
from rll_bt.agent import TREE_OUTPUTS, default_trees_dir, output_problems
from rll_bt.agenttask import KINDS as TREE_KINDS
from rll_bt.agenttask import read_task
from rll_bt.cli import main
from rll_bt.tree import default_registry, parse_tree
from tests.support import TREES
from tests.support.agents import make_task

ALL_FILES = sorted(TREES.rglob("*.yaml"))
TM = msgs.message_set("team")

#: one sample task per kind, as the team server sends them
SAMPLES = {
    "explore_zone": {"zone": 6},
    "get_workpiece": {"machine": "C-CS1", "side": "SHELF", "shelf_slot": 1},
    "put_workpiece": {"machine": "C-RS1", "side": "SLIDE"},
    "retrieve_cap": {"machine": "C-CS1", "shelf_slot": 0},
    "mount_ring": {"machine": "C-RS1", "ring_color": "RING_GREEN"},
    "mount_cap": {"machine": "C-CS2", "cap_color": "CAP_BLACK"},
    "deliver": {"machine": "C-DS", "gate": 3},
    "discard": {},
    "go_to": {"x": 1.0, "y": 1.0, "zone": 5},
}


def sample_params(kind: str) -> dict:
    at, detail = make_task(kind, **SAMPLES[kind])
    return read_task(at, detail, profile=rules.profile("rcll2016"), robot_id=1)[1]


def test_the_agent_finds_these_trees():
    assert default_trees_dir().resolve() == TREES


@pytest.mark.parametrize("kind", TREE_KINDS)
def test_a_tree_for_every_task_kind(kind):
    assert (TREES / f"{kind}.yaml").is_file()


@pytest.mark.parametrize("path", ALL_FILES, ids=lambda p: str(p.relative_to(TREES)))
def test_every_file_validates(path):
    spec = parse_tree(path)
    assert spec.count() > 0


def test_the_cli_validates_them_all(capsys):
    assert main(["tree", "validate", *map(str, ALL_FILES)]) == 0
    out = capsys.readouterr().out
    assert out.count(": ok") == len(ALL_FILES)
    assert "explore_zone.yaml: ok (" in out and "outputs: found)" in out


@pytest.mark.parametrize("kind", TREE_KINDS)
def test_each_tree_loads_with_the_fields_the_agent_gives(kind):
    params = sample_params(kind)
    spec = parse_tree(TREES / f"{kind}.yaml", task=params, strict=True)
    assert set(spec.task) <= set(params), f"{kind}.yaml declares fields the agent never gives"


def test_the_trees_use_skill_nodes_and_recoveries():
    used: dict[str, set[str]] = {}
    for kind in TREE_KINDS:
        spec = parse_tree(TREES / f"{kind}.yaml")
        types = set()

        def walk(ns, types=types):
            types.add(ns.type)
            for kids in ns.slots.values():
                for k in kids:
                    walk(k)
        walk(spec.root)
        used[kind] = types
        assert "recovery" in types, f"{kind} has no recovery"
        assert {"stop_robot", "fail_with_error"} <= types, f"{kind} has no final give-up branch"
    skills = {name for name, nt in default_registry().types().items() if nt.module.startswith("skills")}
    assert used["explore_zone"] >= {"explore_zone", "relocalise", "back_off", "localised"} and \
        used["explore_zone"] & skills
    for kind in ("get_workpiece", "retrieve_cap"):
        assert used[kind] >= {"approach_station", "grab", "holding_workpiece", "back_off", "relocalise"}
    for kind in ("put_workpiece", "mount_ring", "mount_cap", "deliver", "retrieve_cap", "discard"):
        assert used[kind] >= {"approach_station", "put", "holding_workpiece", "back_off", "relocalise"}


@pytest.mark.parametrize("kind", TREE_KINDS)
def test_each_tree_declares_the_outputs_the_agent_reads(kind):
    """explore_zone.yaml declares `found` (the agent reports it in ZoneExplored)
    where the skill node writes it; the agent reads it through `tree.outputs()`."""
    spec = parse_tree(TREES / f"{kind}.yaml")
    assert output_problems(kind, spec) == []
    assert set(spec.outputs) == set(TREE_OUTPUTS.get(kind, {}))


def test_a_tree_without_the_output_is_named_at_the_agents_start(tmp_path):
    text = (TREES / "explore_zone.yaml").read_text()
    start, end = text.index("outputs:"), text.index("root:")
    (tmp_path / "explore_zone.yaml").write_text(text[:start] + text[end:])
    spec = parse_tree(tmp_path / "explore_zone.yaml", search_path=[TREES])
    assert output_problems("explore_zone", spec) == [
        "explore_zone.yaml declares no output 'found' (list), which the agent reads"]
