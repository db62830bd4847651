"""``actorbt xml export``: missions as BehaviorTree.CPP v4 XML. Every exported document is
checked against BT.CPP v4's structure (an independent checker below), and ``xml import``
of it must give the same trees (the parsed models compared): every tree of trees/ against
the project's actor catalog, and hand-written trees that use every control node."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

from bt_engine import Runtime, SubSystem, actor
from bt_xml import dump_mission, import_files
from bt_xml._compare import mission_differences
from bt_xml._export import ExportError, Exporter, export_tree
from bt_cli.actor_index import ActorIndex
from bt_cli.config import import_object, load_config
from bt_cli.main import main
from bt_engine.trees import STANDARD_BEHAVIOURS, TreeLibrary
from bt_engine.trees._parse import parse_mission

REPO = Path(__file__).resolve().parents[1]
PROJECT_TREES = sorted(p.stem for p in (REPO / "trees").glob("*.yaml"))


# ---------------------------------------------------------------- BT.CPP v4 structure

#: BehaviorTree.CPP 4's built-in nodes: kind and ports (src/bt_factory.cpp and the nodes' providedPorts)
BUILTIN = {
    **{
        n: ("Control", set())
        for n in (
            "Sequence",
            "Fallback",
            "ReactiveSequence",
            "ReactiveFallback",
            "SequenceWithMemory",
            "IfThenElse",
            "WhileDoElse",
        )
    },
    "Parallel": ("Control", {"success_count", "failure_count"}),
    **{n: ("Decorator", set()) for n in ("Inverter", "ForceSuccess", "ForceFailure", "KeepRunningUntilFailure")},
    "RetryUntilSuccessful": ("Decorator", {"num_attempts"}),
    "Repeat": ("Decorator", {"num_cycles"}),
    "Timeout": ("Decorator", {"msec"}),
    "Delay": ("Decorator", {"delay_msec"}),
    "RunOnce": ("Decorator", {"then_skip"}),
    "Precondition": ("Decorator", {"if", "else"}),
    "Sleep": ("Action", {"msec"}),
    "SetBlackboard": ("Action", {"value", "output_key"}),
    "Script": ("Action", {"code"}),
    "ScriptCondition": ("Condition", {"code"}),
    "AlwaysSuccess": ("Action", set()),
    "AlwaysFailure": ("Action", set()),
}
RESERVED = {
    "_skipIf",
    "_successIf",
    "_failureIf",
    "_while",
    "_onSuccess",
    "_onFailure",
    "_onHalted",
    "_post",
    "_autoremap",
    "_uid",
    "_fullpath",
    "name",
    "ID",
}
UNSIGNED = {"msec", "delay_msec"}


def allowed_port_name(name: str) -> bool:
    """BT.CPP's IsAllowedPortName: a letter first, no forbidden characters, not reserved."""
    return (
        bool(name)
        and name[0].isalpha()
        and not any(c in name for c in " \t\n\"'&<>{}[]()/\\,;:*=?|!@#$%^~`")
        and name not in RESERVED
    )


def bt_cpp_v4_problems(text: str) -> list[str]:
    """What in an XML document BehaviorTree.CPP v4 (and Groot2) would not accept."""
    root = ET.fromstring(text)
    bad: list[str] = []
    if root.tag != "root" or root.get("BTCPP_format") != "4":
        return [
            f'document element <{root.tag} BTCPP_format={root.get("BTCPP_format")}>, expected <root BTCPP_format="4">'
        ]
    trees = {t.get("ID"): t for t in root.findall("BehaviorTree")}
    if root.get("main_tree_to_execute") not in trees:
        bad.append(f"main_tree_to_execute={root.get('main_tree_to_execute')!r} names no <BehaviorTree>")
    models = root.findall("TreeNodesModel")
    if len(models) != 1:
        bad.append(f"{len(models)} <TreeNodesModel>, expected one")
        return bad
    for child in root:
        if child.tag not in ("BehaviorTree", "TreeNodesModel"):
            bad.append(f"<{child.tag}> in <root>")
    declared: dict[str, tuple[str, dict[str, str]]] = {}
    for node in models[0]:
        if node.tag not in ("Action", "Condition", "Control", "Decorator", "SubTree") or not node.get("ID"):
            bad.append(f"model entry <{node.tag} ID={node.get('ID')}>")
            continue
        ports: dict[str, str] = {}
        tags = [p.tag for p in node]
        if "description" in tags and tags.index("description") != len(tags) - 1:
            bad.append(f"model {node.get('ID')}: <description> before the ports")
        for port in node:
            if port.tag == "description":
                continue
            if port.tag not in ("input_port", "output_port", "inout_port") or not allowed_port_name(
                port.get("name", "")
            ):
                bad.append(f"model {node.get('ID')}: port <{port.tag} name={port.get('name')!r}>")
            ports[port.get("name", "")] = port.tag
        if node.get("ID") in declared or node.get("ID") in BUILTIN:
            bad.append(f"model {node.get('ID')} declared twice or a built-in")
        declared[node.get("ID")] = (node.tag, ports)
    for tree_id, tree in trees.items():
        if tree_id not in declared or declared[tree_id][0] != "SubTree":
            bad.append(f"tree {tree_id} is not declared as <SubTree> in the model")
        if len(tree) != 1:
            bad.append(f"<BehaviorTree ID={tree_id}> has {len(tree)} root nodes")
        for element in tree.iter():
            if element is not tree:
                bad.extend(f"{tree_id}: {p}" for p in node_problems(element, declared, trees))
    return bad


def node_problems(el: ET.Element, declared: dict, trees: dict) -> list[str]:
    tag = el.tag
    attrs = {k: v for k, v in el.attrib.items() if k not in ("name",)}
    if tag == "SubTree":
        tree_id = attrs.pop("ID", None)
        if tree_id not in trees:
            return [f"<SubTree ID={tree_id}> calls no tree of the file"]
        kind, ports = "SubTree", declared[tree_id][1]
    elif tag in BUILTIN:
        kind, names = BUILTIN[tag]
        ports = {n: "input_port" for n in names}
    elif tag in ("Action", "Condition") and attrs.get("ID") in declared:
        # the long form: BehaviorTree.CPP builds the declared node whatever the tag says
        kind, ports = tag, declared[attrs.pop("ID")][1]
    elif tag in declared:
        kind, ports = declared[tag]
    else:
        return [f"<{tag}> is neither built in nor declared"]
    out = [f"<{tag}> has attribute {a!r}, not a port of its model" for a in attrs if a not in ports]
    out += [f"<{tag} {a}={v!r}>: not an unsigned number" for a, v in attrs.items() if a in UNSIGNED and not v.isdigit()]
    n = len(el)
    if (
        kind == "Control"
        and n < 1
        or kind == "Decorator"
        and n != 1
        or kind in ("Action", "Condition", "SubTree")
        and n
    ):
        out.append(f"<{tag}> ({kind}) has {n} children")
    if tag in ("IfThenElse", "WhileDoElse") and n not in (2, 3):
        out.append(f"<{tag}> has {n} children, expected 2 or 3")
    return out


# ---------------------------------------------------------------- round trip


def round_trip(library: TreeLibrary, name: str, tmp_path: Path, resolve: Any) -> tuple[str, dict[str, list[str]]]:
    """Export tree ``name``, check the XML's structure, import it; the differences per tree."""
    text = export_tree(name, library, resolve)
    assert bt_cpp_v4_problems(text) == []
    path = tmp_path / f"{name}.xml"
    path.write_text(text, encoding="utf-8")
    missions = import_files([path])
    exported = [m.name for m in Exporter(library).trees_of(name)]
    assert list(missions) == exported  # the tree, then what it calls
    back = TreeLibrary(resolve, STANDARD_BEHAVIOURS)
    for tree, mission in missions.items():
        back.add(parse_mission(dump_mission(mission), f"{tree}.yaml"))
    back.check()  # the imported missions validate against the same catalog
    diffs = {
        tree: mission_differences(library[tree], back[tree], lambda a: library.resolve(a).signature)
        for tree in missions
    }
    return text, {t: d for t, d in diffs.items() if d}


@pytest.fixture(scope="module")
def project() -> TreeLibrary:
    """The trees folder against the project's actor catalog, built as ``actorbt check``
    builds it (the actor index of actorbt.yaml's subsystems), without touching .actorbt/."""
    cfg = load_config(REPO / "actorbt.yaml")
    with Runtime(clock="virtual") as rt:
        for name, spec in cfg.subsystems.items():
            rt.add_subsystem(name, import_object(spec, name))
        index = ActorIndex.of(rt.root.all_actors())
    library = TreeLibrary(index.resolve, STANDARD_BEHAVIOURS)
    library.load_folder(cfg.trees_dir())
    library.check()
    return library


@pytest.mark.parametrize("tree", PROJECT_TREES)
def test_every_project_tree_round_trips(project: TreeLibrary, tree: str, tmp_path: Path) -> None:
    _, diffs = round_trip(project, tree, tmp_path, project.resolver)
    assert diffs == {}


def test_the_node_model_comes_from_the_catalog(project: TreeLibrary, tmp_path: Path) -> None:
    text, _ = round_trip(project, "bt_pick_place", tmp_path, project.resolver)
    root = ET.fromstring(text)
    assert root.get("main_tree_to_execute") == "bt_pick_place"
    assert [t.get("ID") for t in root.findall("BehaviorTree")] == [
        "bt_pick_place",
        "bt_search",
        "bt_catch",
        "bt_carry",
        "reset",
    ]
    model = {e.get("ID"): e for e in root.find("TreeNodesModel")}
    goto = {p.get("name"): p for p in model["goto"]}
    assert model["goto"].tag == "Action"
    assert goto["x"].tag == "input_port" and goto["x"].get("type") == "double"
    assert goto["x"].text == "goal x in the map frame [m]"
    search = {p.get("name"): p for p in model["bt_search"]}
    assert model["bt_search"].tag == "SubTree"
    assert search["category"].get("default") == "any" and search["category"].text == "can, bottle, or any"
    assert search["locations"].get("default") == "json:[]" and search["locations"].get("type") == "list"
    assert search["found"].tag == "output_port"
    assert search["result"].get("type") == "actorbt::outputs"
    assert model["bt_search"].find("description").text.startswith("Drive through the search locations")
    call = root.find(".//SubTree[@ID='bt_search']")
    assert call.attrib == {
        "ID": "bt_search",
        "name": "search",
        "category": "{category}",
        "locations": "{locations}",
        "result": "{search}",
    }


# ---------------------------------------------------------------- every control node


class Parts(SubSystem):
    """Small actors for the hand-written trees."""

    @actor
    def move(self, x: float, y: float = 0.0, label: str = "here") -> dict:
        """Move.

        Args:
            x: where [m]
            y: where [m]
            label: a name
        """
        return {"x": x, "y": y}

    @actor
    def ready(self) -> bool:
        """Whether it is ready."""
        return True

    @actor
    def echo(self, value: Any = None, items: list | None = None, timeout: float | None = None) -> Any:
        """The value back.

        Args:
            value: anything
            items: a list
            timeout: a time [s]
        """
        return value


SUB = """
name: sub
doc: A called tree.
inputs:
  goal: {type: dict, doc: where to go}
  speed: {type: float, default: 0.5}
  mode: {type: str, default: "1"}
  extra: {type: any, default: null}
outputs:
  reached: {type: dict, doc: where it got}
  count: int
root:
  sequence:
    - {do: move, with: {x: "{goal.x}", y: "{goal.y}"}, out: reached}
    - set: {count: 1}
"""

CONTROLS = """
name: controls
doc: Every control node, decorator and leaf a mission has.
inputs:
  n: {type: int, default: 2}
  t: {type: float, default: 1.5}
  where: {type: dict, default: {x: 1.0, y: 2.0}}
  names: {type: list, default: [a, "{b}", "3"]}
  target: str
outputs: [out1, pair, total]
root:
  name: all
  sequence:
    - reactive_sequence: [{do: ready}, {do: move, with: [1.0, 2]}]
    - selector: [{check: n > 1 and t <= 2.0 or not flag}, {name: named check, check: (n == 2)}]
    - fallback: [{check: target in names}, {check: where.x == 1}, {check: "null == null"}]
    - reactive_selector: [{do: ready}, {do: echo, with: {value: "{where.x}"}}]
    - parallel: [{do: ready}, {do: ready}]
    - parallel: {policy: success_on_one, children: [{do: ready}, {wait: 0.25}]}
    - parallel:
        policy: success_on_selected
        selected: [ready, w]
        children: [{name: ready, do: ready}, {name: w, wait: 0.1}, {do: echo}]
    - parallel: {success_count: 2, failure_count: -1, children: [{do: ready}, {do: ready}, {do: ready}]}
    - parallel: {success_count: -1, failure_count: 1, children: [{do: ready}, {do: ready}]}
    - resume_sequence: [{do: ready}, {do: ready}]
    - pipeline_sequence: [{do: ready}, {do: ready}]
    - if_then_else: [{check: n > 0}, {do: ready}, {do: ready}]
    - if_then_else: [{check: n > 0}, {do: ready}]
    - while_do_else: [{check: "-n < 0"}, {do: ready}, {set: {flag: true}}]
    - recovery: {retries: 2, children: [{do: ready}, {do: ready}]}
    - recovery: {retries: "{n}", children: [{do: ready}, {do: ready}]}
    - retry: {times: 3, child: {do: ready}}
    - retry: {times: forever, child: {do: ready}}
    - retry: {times: "{n}", child: {do: ready}}
    - repeat: {times: 2, child: {do: ready}}
    - force_success: {repeat: {child: {do: ready}}}
    - repeat: {times: "{n}", child: {do: ready}}
    - timeout: {seconds: 2.5, child: {do: ready}}
    - timeout: {seconds: 0.0005, child: {do: ready}}
    - timeout: {seconds: "{t}", child: {do: ready}}
    - rate_controller: {hz: 2.0, child: {do: ready}}
    - rate_controller: {hz: "{t}", child: {do: ready}}
    - run_once: {do: ready}
    - run_once: {then: success, child: {do: ready}}
    - run_once: {then: failure, child: {do: ready}}
    - selector:
        - run_once: {then: success, child: {do: ready}}
        - run_once: {then: failure, child: {do: ready}}
        - reactive_selector: [{run_once: {then: same, child: {do: ready}}}]
    - invert: {do: ready}
    - force_failure: {force_success: {do: ready}}
    - {name: call, do: move, with: {x: 1, y: "{where.y}", label: "{{literal}}"}, out: out1}
    - {do: move, with: {x: "{t}", label: "42"}}
    - {do: echo, with: {value: [1, "{n}", {k: "{where}"}], items: [], timeout: 2.0}, out: echoed}
    - {do: echo, with: {value: "json:not", timeout: null}}
    - {do: echo, with: {value: "true", items: ["x"]}}
    - {do: echo, with: {value: "two\\nlines"}}
    - {name: guard, condition: echo, with: {value: true}, out: guarded}
    - {name: to sub, do: sub, with: {goal: "{where}", mode: "2"}, out: result}
    - {do: sub, with: {goal: {x: 0, y: "{t}"}, speed: 1}}
    - set: {pair: [1, 2]}
    - set: {a: 1, b: 'x', c: "{n}", d: -2.5, e: false}
    - set: {f: "{a}", a: 2}
    - set: {total: "{result.count}", g: "it's \\"quoted\\""}
    - set: {h: "{{braces}}"}
    - wait: 1
    - wait: "{t}"
    - wait: 0.0001
    - {name: spin, behaviour: Running}
    - {behaviour: SuccessEveryN, with: {n: "{n}"}, writes: [w1]}
    - {check: "true"}
"""


@pytest.fixture(scope="module")
def parts() -> Any:
    with Runtime(clock="virtual") as rt:
        rt.add_subsystem("parts", Parts)
        return ActorIndex.of(rt.root.all_actors())


def hand_written(parts: Any, *texts: str) -> TreeLibrary:
    library = TreeLibrary(parts.resolve, STANDARD_BEHAVIOURS)
    for i, text in enumerate(texts):
        library.add(parse_mission(text, f"tree{i}.yaml"))
    library.check()
    return library


def test_every_control_node_round_trips(parts: Any, tmp_path: Path) -> None:
    library = hand_written(parts, SUB, CONTROLS)
    text, diffs = round_trip(library, "controls", tmp_path, parts.resolve)
    assert diffs == {}
    root = ET.fromstring(text)
    tags = {e.tag for e in root.find("BehaviorTree").iter()}
    # the built-ins where BT.CPP has one, Nav2's and actorbt's own nodes elsewhere
    assert {
        "ReactiveSequence",
        "Fallback",
        "ReactiveFallback",
        "Parallel",
        "SequenceWithMemory",
        "IfThenElse",
        "WhileDoElse",
        "RetryUntilSuccessful",
        "Repeat",
        "Timeout",
        "RunOnce",
        "Inverter",
        "ForceSuccess",
        "ForceFailure",
        "SetBlackboard",
        "Script",
        "ScriptCondition",
        "Sleep",
        "SubTree",
        "PipelineSequence",
        "RecoveryNode",
        "RateController",
        "SingleTrigger",
        "ActorbtCheck",
        "ActorbtSet",
        "ActorbtWait",
        "ActorbtTimeout",
        "ActorbtParallel",
        "ActorbtRunOnce",
        "ActorbtBehaviour",
    } <= tags
    model = {e.get("ID"): e.tag for e in root.find("TreeNodesModel")}
    # a leaf's kind is how the tree uses it: echo is called with do: first, so its model
    # says Action and its condition: use names the kind in the long form
    assert model["ready"] == "Action" and model["move"] == "Action" and model["ActorbtCheck"] == "Condition"
    assert model["echo"] == "Action" and root.find(".//Condition[@ID='echo']") is not None


def test_values_are_plain_where_plain_text_reads_back(parts: Any, tmp_path: Path) -> None:
    library = hand_written(parts, SUB, CONTROLS)
    root = ET.fromstring(export_tree("controls", library, parts.resolve))
    call = root.find(".//move[@name='call']")
    assert call.attrib == {
        "name": "call",
        "x": "1",
        "y": "{where.y}",
        "label": 'json:"{{literal}}"',
        "result": "{out1}",
    }
    assert root.find(".//move[@label='42']") is not None  # a string port: "42" reads back as text
    assert root.find(".//echo[@value='true']").get("items") == 'json:["x"]'
    assert root.find(".//echo[@value='json:\"json:not\"']") is not None  # text that looks like json:
    assert root.find('.//ScriptCondition[@code="n > 1 && t <= 2.0 || !flag"]') is not None
    assert root.find(".//Script").get("code") == "a := 1; b := 'x'; c := n; d := -2.5; e := false"
    assert root.find(".//Timeout").get("msec") == "2500"


def test_an_argument_bt_cpp_cannot_name_is_a_located_error(tmp_path: Path) -> None:
    class Named(SubSystem):
        @actor
        def label(self, name: str) -> None:
            """Label."""

    with Runtime(clock="virtual") as rt:
        rt.add_subsystem("named", Named)
        index = ActorIndex.of(rt.root.all_actors())
    library = hand_written(index, "name: t\nroot:\n  sequence:\n    - {do: label, with: {name: x}}\n")
    with pytest.raises(ExportError) as err:
        export_tree("t", library, index.resolve)
    assert str(err.value).startswith("tree0.yaml:4:")
    assert "'name'" in str(err.value)


# ---------------------------------------------------------------- the command


@pytest.fixture
def config(tmp_path: Path) -> str:
    trees = tmp_path / "trees"
    trees.mkdir()
    (trees / "demo_patrol.yaml").write_text((REPO / "trees" / "demo_patrol.yaml").read_text())
    (trees / "broken.yaml").write_text("name: broken\nroot: {do: no_such_actor}\n")
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems: {}\ntrees: trees\n")
    return str(cfg)


def test_xml_export_writes_a_file_that_imports_back(config: str, tmp_path: Path, capsys) -> None:
    out = tmp_path / "patrol.xml"
    assert main(["--config", config, "xml", "export", "demo_patrol", "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    assert bt_cpp_v4_problems(out.read_text()) == []
    assert main(["xml", "import", str(out), "--out", str(tmp_path / "back")]) == 0
    assert (tmp_path / "back" / "demo_patrol.yaml").is_file()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["demo_patrl"], "unknown tree 'demo_patrl' (did you mean 'demo_patrol'?)"),
        (["broken"], "unknown actor"),
    ],
)
def test_xml_export_errors_are_one_line(config: str, tmp_path: Path, capsys, argv: list[str], message: str) -> None:
    assert main(["--config", config, "xml", "export", *argv, "--out", str(tmp_path / "x.xml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "x.xml").exists()
