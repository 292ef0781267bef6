"""BehaviorTree.CPP v4 XML (Groot2): a YAML tree written and read back unchanged, the node model, errors located by line."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import py_trees
import pytest
import yaml

from executive.cli import main
from executive.mission.errors import MissionError
from executive.mission.loader import load_mission
from executive.tree import select as mission_tree
from executive.tree.formats.btcpp import NodeType, Port, Slot, from_yaml, read_xml, to_yaml, write_xml

#: BehaviorTree.CPP's built-in node IDs an export writes.
BUILT_INS = {"Sequence", "ReactiveSequence", "Fallback", "ReactiveFallback", "Parallel", "Inverter", "RetryUntilSuccessful", "Repeat", "Timeout"}

TYPES = {
    t.id: t
    for t in (
        NodeType("sequence", "composite", "Its children in order.", (Port("memory", "bool", True, doc="keeps going"),), (Slot("children", True),)),
        NodeType("timeout", "decorator", "FAILURE after a while.", (Port("timeout_s", "float", required=True, unit="s"),), (Slot("child", False),)),
        NodeType("ekf_ok", "guard", "The EKF is usable.", (Port("variance_threshold", "float", 0.8),)),
        NodeType("set_mode", "action", "Asks for a mode.", (Port("mode", "str", required=True), Port("limit", "range", None, nullable=True))),
        NodeType("failsafe_guarded", "decorator", "Work under guards.", (), (Slot("work", False), Slot("guards", True, required=False))),
        NodeType("preflight", "subtree", "EKF, then arm."),
    )
}

TREE = {
    "node": "sequence",
    "name": "Run",
    "children": [
        {"use": "preflight"},
        {
            "node": "failsafe_guarded",
            "work": {"node": "timeout", "timeout_s": 30.5, "child": {"node": "set_mode", "mode": "GUIDED", "limit": {"min": 1.0, "max": 2.5}}},
            "guards": [{"node": "ekf_ok", "name": "EKF ok?", "variance_threshold": 0.5}, "ekf_ok"],
        },
        {"node": "sequence", "memory": False, "children": [{"node": "set_mode", "mode": "HOLD", "limit": None}]},
    ],
}


def test_a_yaml_tree_written_as_xml_reads_back_the_same() -> None:
    text = write_xml(from_yaml(TREE, TYPES), TYPES)
    assert to_yaml(read_xml(text, "t.xml", TYPES), TYPES) == TREE


def test_the_document_is_btcpp_v4_with_a_model_of_every_node_type() -> None:
    doc = ET.fromstring(write_xml(from_yaml(TREE, TYPES), TYPES))
    assert (doc.tag, doc.attrib) == ("root", {"BTCPP_format": "4", "main_tree_to_execute": "MainTree"})
    tree, model = doc
    assert (tree.tag, tree.attrib["ID"], len(tree)) == ("BehaviorTree", "MainTree", 1)
    assert tree[0].tag == "Sequence" and tree[0].attrib == {"name": "Run"}  # memory: true, BehaviorTree.CPP's Sequence
    guarded = tree[0][1]
    assert (guarded.tag, guarded.attrib, [c.tag for c in guarded]) == ("failsafe_guarded", {}, ["ReactiveSequence"])
    assert [c.tag for c in guarded[0]] == ["ekf_ok", "ekf_ok", "Timeout"]  # the guards, then the work, as it ticks them
    assert guarded[0][2].attrib == {"msec": "30500"} and guarded[0][2][0].attrib == {"mode": "GUIDED", "limit": "1.0;2.5"}
    assert (tree[0][2].tag, tree[0][2].attrib) == ("ReactiveSequence", {})  # memory: false
    assert {(m.tag, m.attrib["ID"]) for m in model} == {  # sequence and timeout are written as built-ins: not declared
        ("Condition", "ekf_ok"),
        ("Action", "set_mode"),
        ("Decorator", "failsafe_guarded"),
        ("Action", "preflight"),
    }
    ports = {m.attrib["ID"]: m for m in model}
    variance = ports["ekf_ok"].find("input_port")
    assert variance is not None and variance.attrib == {"name": "variance_threshold", "type": "double", "default": "0.8"}
    limit = ports["set_mode"].findall("input_port")[1]
    assert limit.attrib == {"name": "limit", "type": "std::vector<double>", "default": "null"} and limit.text == " (min;max)"
    assert ports["failsafe_guarded"].findtext("description") == (
        "Work under guards. Its one child: a ReactiveSequence of the guards (any number), then the work (one)."
    )


def test_unknown_node_types_and_bad_ports_are_named_with_their_line() -> None:
    text = """<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <sequence memory="perhaps">
      <MoveBase goal="{target}"/>
      <Action ID="set_mode" mode="{m}"/>
      <timeout timeout_s="5"/>
      <ekf_ok colour="red"/>
    </sequence>
  </BehaviorTree>
</root>
"""
    with pytest.raises(MissionError) as caught:
        read_xml(text, "t.xml", TYPES)
    assert [str(e) for e in caught.value.errors] == [
        "t.xml:3:5: Main/sequence.memory: 'perhaps': not true or false",
        "t.xml:4:7: Main/sequence/MoveBase: unknown node type 'MoveBase' (not in the catalogue: executive behaviours lists it)",
        "t.xml:5:7: Main/sequence/set_mode.mode: '{m}': a blackboard reference ({key}) is not supported here: give the value",
        "t.xml:6:7: Main/sequence/timeout: timeout takes exactly 1 child node (child), has 0",
        "t.xml:7:7: Main/sequence/ekf_ok.colour: unknown port (ports of ekf_ok: variance_threshold)",
    ]


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ("<root BTCPP_format='4'><BehaviorTree ID='A'>", "t.xml:1:45: (file): not well-formed XML: no element found"),
        (
            "<root BTCPP_format='3'><BehaviorTree><ekf_ok/></BehaviorTree></root>",
            "t.xml:1:1: root.BTCPP_format: '3': only BehaviorTree.CPP format 4 is read",
        ),
        (
            "<root BTCPP_format='4' main_tree_to_execute='B'><BehaviorTree ID='A'><ekf_ok/></BehaviorTree></root>",
            "t.xml:1:1: root.main_tree_to_execute: no <BehaviorTree ID='B'> in the file",
        ),
        ("<!DOCTYPE r [<!ENTITY a 'b'>]><root/>", "t.xml:1:13: (file): a DTD is not allowed"),
        ("<tree/>", 't.xml:1:1: tree: the document\'s element must be <root BTCPP_format="4">'),
    ],
)
def test_what_is_not_a_btcpp_4_tree_is_refused(text: str, error: str) -> None:
    with pytest.raises(MissionError) as caught:
        read_xml(text, "t.xml", TYPES)
    assert [str(e) for e in caught.value.errors] == [error]


GROOT_FILE = """<?xml version="1.0" encoding="UTF-8"?>
<root BTCPP_format="4" main_tree_to_execute="Patrol">
  <BehaviorTree ID="Patrol">
    <sequence name="Run" _uid="1">
      <Action ID="preflight"/>
      <failsafe_guarded>
        <for_each_leg>
          <use_leg/>
        </for_each_leg>
        <link_alive/>
        <armed hold_after_s="2"/>
      </failsafe_guarded>
      <set_mode mode="HOLD" name="Hold at the end"/>
    </sequence>
  </BehaviorTree>
  <TreeNodesModel/>
</root>
"""


def test_import_reads_a_groot2_file_into_a_tree_section(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    xml = tmp_path / "patrol.xml"
    xml.write_text(GROOT_FILE.replace("use_leg", "guided_leg"), encoding="utf-8")
    assert main(["import", str(xml), "-o", str(tmp_path / "tree.yaml")]) == 0, capsys.readouterr().err
    assert yaml.safe_load((tmp_path / "tree.yaml").read_text(encoding="utf-8")) == {
        "tree": {
            "node": "sequence",
            "name": "Run",
            "children": [
                {"use": "preflight"},
                {
                    "node": "failsafe_guarded",
                    "work": {"node": "for_each_leg", "child": {"use": "guided_leg"}},
                    "guards": ["link_alive", {"node": "armed", "hold_after_s": 2.0}],
                },
                {"node": "set_mode", "name": "Hold at the end", "mode": "HOLD"},
            ],
        }
    }


def test_import_names_unknown_node_types_with_their_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    xml = tmp_path / "patrol.xml"
    xml.write_text(GROOT_FILE, encoding="utf-8")
    assert main(["import", str(xml), "-o", str(tmp_path / "tree.yaml")]) == 2
    assert capsys.readouterr().err == (
        f"{xml}:8:11: Patrol/sequence/failsafe_guarded/for_each_leg/use_leg: "
        "unknown node type 'use_leg' (not in the catalogue: executive behaviours lists it)\n"
    )
    assert not (tmp_path / "tree.yaml").exists()


MISSIONS = Path(__file__).parents[2] / "missions"


def described(root: py_trees.behaviour.Behaviour) -> list[tuple[str, str, dict[str, Any]]]:
    """Every node of a built tree: its class, its name and its plain attributes (the behaviours it holds by name)."""

    def plain(value: Any) -> Any:
        return value.name if isinstance(value, py_trees.behaviour.Behaviour) else tuple(map(plain, value)) if isinstance(value, tuple) else value

    kept = (int, float, str, bool, tuple, type(None))
    return [
        (type(n).__name__, n.name, {k: plain(v) for k, v in vars(n).items() if not k.startswith("_") and k != "id" and isinstance(v, kept)})
        for n in root.iterate()
    ]


@pytest.mark.parametrize("name", ["rover_square", "asv_sampling", "auv_survey", "vtol_transit"])
def test_a_built_in_tree_exported_and_imported_builds_the_same_tree(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    original = MISSIONS / f"{name}.yaml"
    xml, edited = tmp_path / "tree.xml", tmp_path / "edited.yaml"
    assert main(["export", str(original), "-o", str(xml)]) == 0
    warnings = capsys.readouterr().err.splitlines()
    doc = ET.parse(xml).getroot()
    model = {m.attrib["ID"] for m in doc.find("TreeNodesModel") or ()}
    assert {e.tag for e in list(doc.find("BehaviorTree").iter())[1:]} <= model | BUILT_INS  # a built-in, or ours described
    assert not model & {"sequence", "selector", "parallel", "inverter", "retry", "repeat", "timeout"}  # those are written as built-ins
    assert main(["import", str(xml), "--mission", str(original), "-o", str(edited)]) == 0, capsys.readouterr().err
    assert isinstance(load_mission(edited).tree, dict)  # a tree written in the mission file now
    assert described(mission_tree.build(load_mission(edited))) == described(
        mission_tree.build(load_mission(original))
    )  # node for node, parameters too
    differs = "once is written as our own decorator: BehaviorTree.CPP's RunOnce keeps its child's first FAILURE for good"
    assert all(("SpeedWithin" in w and "tolerance_" in w) or differs in w for w in warnings), warnings  # what is not exact is said
    assert sum(differs in w for w in warnings) == {"auv_survey": 1, "vtol_transit": 4}.get(name, 0)


def test_the_shipped_yaml_tree_exported_and_imported_is_the_same_yaml(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mission = MISSIONS / "asv_sampling_yaml_tree.yaml"
    assert main(["export", str(mission), "--format", "btcpp", "-o", str(tmp_path / "tree.xml")]) == 0
    assert main(["import", str(tmp_path / "tree.xml"), "-o", str(tmp_path / "tree.yaml")]) == 0
    assert capsys.readouterr().err == ""
    assert yaml.safe_load((tmp_path / "tree.yaml").read_text(encoding="utf-8")) == {
        "tree": yaml.safe_load(mission.read_text(encoding="utf-8"))["tree"]
    }


def test_the_ugv_tree_exports_and_imports_back_as_a_tree_section(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # (its mission starts with no waypoints, which only the named tree ugv_rc_route allows: --mission would be refused for that)
    assert main(["export", str(MISSIONS / "ugv_rc_route.yaml"), "-o", str(tmp_path / "tree.xml")]) == 0
    assert main(["import", str(tmp_path / "tree.xml"), "-o", str(tmp_path / "tree.yaml")]) == 0, capsys.readouterr().err
    tree = yaml.safe_load((tmp_path / "tree.yaml").read_text(encoding="utf-8"))["tree"]
    assert tree["node"] == "unless_paused" and "- route_edit_switch" in (tmp_path / "tree.yaml").read_text(encoding="utf-8")


def test_behaviortree_cpp_built_in_nodes_groot2_offers_are_read_as_ours(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    xml = tmp_path / "builtins.xml"
    xml.write_text(
        """<root BTCPP_format="4"><BehaviorTree ID="T">
  <Sequence>
    <ReactiveSequence name="Guarded"><link_alive/><Fallback><armed/><Inverter><armed/></Inverter></Fallback></ReactiveSequence>
    <RetryUntilSuccessful num_attempts="3"><arm/></RetryUntilSuccessful>
    <Repeat num_cycles="2"><disarm/></Repeat>
    <ReactiveFallback><armed/><disarm/></ReactiveFallback>
    <SequenceWithMemory><arm/></SequenceWithMemory>
  </Sequence>
</BehaviorTree></root>""",
        encoding="utf-8",
    )
    assert main(["import", str(xml)]) == 2  # SequenceWithMemory does not start over after a failure: nothing of ours does that
    assert (
        capsys.readouterr().err
        == f"{xml}:7:5: T/Sequence/SequenceWithMemory: unknown node type 'SequenceWithMemory' (not in the catalogue: executive behaviours lists it)\n"
    )
    xml.write_text(xml.read_text(encoding="utf-8").replace("    <SequenceWithMemory><arm/></SequenceWithMemory>\n", ""), encoding="utf-8")
    assert main(["import", str(xml)]) == 0
    assert yaml.safe_load(capsys.readouterr().out) == {
        "tree": {
            "node": "sequence",  # memory: true, the default
            "children": [
                {
                    "node": "sequence",
                    "name": "Guarded",
                    "memory": False,
                    "children": ["link_alive", {"node": "selector", "memory": True, "children": ["armed", {"node": "inverter", "child": "armed"}]}],
                },
                {"node": "retry", "failures": 3, "child": "arm"},
                {"node": "repeat", "successes": 2, "child": "disarm"},
                {"node": "selector", "children": ["armed", "disarm"]},  # memory: false, the default
            ],
        }
    }


def test_a_tree_with_nodes_the_catalogue_lacks_exports_them_said_and_import_refuses_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.syspath_prepend(str(Path(__file__).parents[2] / "examples" / "patrol"))  # the patrol example: a guard and an action of its own
    mission = tmp_path / "patrol.yaml"
    text = (Path(__file__).parents[2] / "examples" / "patrol" / "patrol.yaml").read_text(encoding="utf-8")
    mission.write_text(text.replace("tree: waypoints ", "tree: patrol_tree:build "), encoding="utf-8")
    assert main(["export", str(mission), "-o", str(tmp_path / "tree.xml")]) == 0
    warnings = capsys.readouterr().err
    for cls in ("BeaconOn", "EnoughSatellites", "WaitForGuards"):
        assert f"{cls} is not in the catalogue: Groot2 shows it, import refuses it (warning)" in warnings
    model = ET.parse(tmp_path / "tree.xml").getroot().find("TreeNodesModel")
    assert model is not None and {m.attrib["ID"]: m.tag for m in model if m.attrib["ID"][0].isupper()} == {
        "BeaconOn": "Action",
        "EnoughSatellites": "Condition",
        "WaitForGuards": "Action",
    }
    assert main(["import", str(tmp_path / "tree.xml")]) == 2
    assert [line.split(": ", 2)[2] for line in capsys.readouterr().err.splitlines()] == [
        f"unknown node type '{cls}' (not in the catalogue: executive behaviours lists it)"
        for cls in ("BeaconOn", "EnoughSatellites", "WaitForGuards")
    ]


def test_parallel_and_timeout_are_read_as_ours_and_what_none_of_ours_means_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    xml = tmp_path / "builtins.xml"
    xml.write_text(
        """<root BTCPP_format="4"><BehaviorTree ID="T">
  <Sequence>
    <Parallel success_count="1" failure_count="1"><Timeout msec="2500"><arm/></Timeout><armed/></Parallel>
    <Parallel><armed/><link_alive/></Parallel>
  </Sequence>
</BehaviorTree></root>""",
        encoding="utf-8",
    )
    assert main(["import", str(xml)]) == 0, capsys.readouterr().err
    assert yaml.safe_load(capsys.readouterr().out)["tree"]["children"] == [
        {"node": "parallel", "policy": "success_on_one", "children": [{"node": "timeout", "timeout_s": 2.5, "child": "arm"}, "armed"]},
        {"node": "parallel", "children": ["armed", "link_alive"]},  # BehaviorTree.CPP's defaults -1, 1: success_on_all
    ]
    xml.write_text(
        """<root BTCPP_format="4"><BehaviorTree ID="T">
  <Sequence memory="false">
    <Parallel success_count="2"><armed/><link_alive/></Parallel>
    <Timeout msec="-5"><arm/></Timeout>
    <RetryUntilSuccessful failures="3"><arm/></RetryUntilSuccessful>
  </Sequence>
</BehaviorTree></root>""",
        encoding="utf-8",
    )
    assert main(["import", str(xml)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{xml}:2:3: T/Sequence.memory: unknown port (ports of Sequence: none)",
        f"{xml}:3:5: T/Sequence/Parallel: success_count=2, failure_count=1: no node of ours does that (parallel: -1 or 1, and 1)",
        f"{xml}:4:5: T/Sequence/Timeout.msec: '-5': not a number of milliseconds (0 or more)",
        f"{xml}:5:5: T/Sequence/RetryUntilSuccessful.failures: unknown port (ports of RetryUntilSuccessful: num_attempts)",
    ]


def test_our_nodes_with_several_slots_are_read_grouped_as_export_writes_them_and_as_before() -> None:
    grouped = from_yaml(TREE, TYPES).slots["children"][1]
    text = write_xml(grouped, TYPES)
    assert "<failsafe_guarded>\n      <ReactiveSequence>\n        <ekf_ok" in text
    old = text.replace("<ReactiveSequence>", "").replace("</ReactiveSequence>", "")
    work = old[old.index("<Timeout") : old.index("</Timeout>") + len("</Timeout>")]
    old = old.replace(work, "").replace("<failsafe_guarded>", "<failsafe_guarded>" + work)  # our lower-case form: work, then guards
    assert to_yaml(read_xml(text, "t.xml", TYPES), TYPES) == to_yaml(read_xml(old, "t.xml", TYPES), TYPES) == TREE["children"][1]
