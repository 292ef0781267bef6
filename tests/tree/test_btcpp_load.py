"""BehaviorTree.CPP v4 itself (its Python bindings, behaviortreepy) loads every mission's exported tree and ticks it.

Our leaves and decorators are registered as stubs, as the bindings allow (``register_simple_*``: no
ports, no Control node). BehaviorTree.CPP refuses a port attribute its registered node does not
provide, so the tree loaded is a copy without our nodes' port attributes, and each one removed is
checked declared as an ``input_port`` of its node's ID in the exported ``<TreeNodesModel>``: what a
C++ registration of ours would provide. The built-ins keep theirs.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from executive.cli import main

behaviortreepy = pytest.importorskip("behaviortreepy")
Status = behaviortreepy.NodeStatus

MISSIONS = Path(__file__).parents[2] / "missions"
NAMES = ["rover_square", "boat_survey", "asv_sampling", "asv_sampling_yaml_tree", "auv_survey", "vtol_transit", "ugv_rc_route"]
#: BehaviorTree.CPP's built-ins an export writes (registered by the factory itself).
BUILT_INS = {"Sequence", "ReactiveSequence", "Fallback", "ReactiveFallback", "Parallel", "Inverter", "RetryUntilSuccessful", "Repeat", "Timeout"}


def test_every_shipped_mission_is_loaded_here() -> None:
    assert sorted(p.stem for p in MISSIONS.glob("*.yaml")) == sorted(NAMES)


def exported(name: str, tmp_path: Path) -> ET.Element:
    xml = tmp_path / f"{name}.xml"
    assert main(["export", str(MISSIONS / f"{name}.yaml"), "--format", "btcpp", "-o", str(xml)]) == 0
    return ET.parse(xml).getroot()


def without_our_ports(doc: ET.Element) -> dict[str, set[str]]:
    """Remove the port attributes of our own nodes (in place); what was removed, by node ID."""
    removed: dict[str, set[str]] = {}
    tree = doc.find("BehaviorTree")
    assert tree is not None
    for element in tree.iter():
        if element.tag in BUILT_INS or element is tree:
            continue
        for key in [k for k in element.attrib if k != "name" and not k.startswith("_")]:
            removed.setdefault(element.tag, set()).add(key)
            del element.attrib[key]
    return removed


@pytest.mark.parametrize("name", NAMES)
def test_behaviortree_cpp_loads_the_exported_tree_and_ticks_it(name: str, tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    doc = exported(name, tmp_path)
    model = doc.find("TreeNodesModel")
    assert model is not None
    kinds = {m.attrib["ID"]: m.tag for m in model}
    declared = {m.attrib["ID"]: {p.attrib["name"] for p in m.findall("input_port")} for m in model}
    tree = doc.find("BehaviorTree")
    assert tree is not None
    used = {e.tag for e in tree.iter()} - {"BehaviorTree"}
    assert "Control" not in {kinds[t] for t in used - BUILT_INS}  # the bindings register no Control node of ours
    assert used - BUILT_INS <= set(kinds)  # every node of ours is declared, with its kind

    removed = without_our_ports(doc)
    for node_id, ports in removed.items():
        assert ports <= declared[node_id], f"{node_id}: {ports - declared[node_id]} not declared in the TreeNodesModel"

    ticked: list[str] = []
    factory = behaviortreepy.BehaviorTreeFactory()
    for node_id in sorted(used - BUILT_INS):

        def leaf(node: object, node_id: str = node_id) -> object:
            ticked.append(node_id)
            return Status.SUCCESS

        def decorator(status: object, node: object, node_id: str = node_id) -> object:
            ticked.append(node_id)
            return status

        {
            "Action": factory.register_simple_action,
            "Condition": factory.register_simple_condition,
            "Decorator": factory.register_simple_decorator,
        }[kinds[node_id]](node_id, decorator if kinds[node_id] == "Decorator" else leaf)
    loaded = factory.create_tree_from_text(ET.tostring(doc, encoding="unicode"))
    status = loaded.tick_once()
    assert status in (Status.SUCCESS, Status.FAILURE, Status.RUNNING)
    first_leaf = next(e.tag for e in tree.iter() if len(e) == 0 and e is not tree)
    assert ticked and first_leaf in ticked  # the tick went down to the first leaf through our decorators
    assert "Python exception" not in capfd.readouterr().err
