"""Public trees that import whole: Nav2 Jazzy's twelve navigator trees with Nav2's node
model (tests/data/btxml/nav2_jazzy), the actor demo's pytwb workbench
(tests/data/btxml/pytwb_actor_demo), and plugin controls and decorators through an XML
round trip."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

from bt_xml import BtXmlError, Exporter, import_files, mission_differences, read_node_model, write_missions
from bt_engine.trees import (
    STANDARD_BEHAVIOURS,
    PluginNode,
    TreeLibrary,
    check_files,
    node_plugins,
    parse_mission,
    read_mission,
    walk,
)
from bt_tools.cli import unwritten_plugins
from bt_xml._nodes import convert_literal

DATA = Path(__file__).parent / "data" / "btxml"
NAV2 = DATA / "nav2_jazzy"
NAV2_TREES = sorted(p for p in NAV2.glob("*.xml") if p.name != "nav2_tree_nodes.xml")
PYTWB = DATA / "pytwb_actor_demo"


def test_there_are_twelve_nav2_trees() -> None:
    assert len(NAV2_TREES) == 12


@pytest.mark.parametrize("tree", NAV2_TREES, ids=lambda p: p.stem)
def test_every_nav2_jazzy_tree_imports_and_validates(tree: Path, tmp_path: Path) -> None:
    model = read_node_model([NAV2 / "nav2_tree_nodes.xml"])
    paths = write_missions(import_files([tree], model), tmp_path, tree.name)
    library = TreeLibrary(model.resolver(), STANDARD_BEHAVIOURS, model.plugins(node_plugins()))
    assert check_files(paths, library=library) == []
    # every control and decorator of Nav2's is implemented: nothing left to write
    assert unwritten_plugins(library, paths) == []


def test_nav2_controls_import_as_the_plugins(tmp_path: Path) -> None:
    model = read_node_model([NAV2 / "nav2_tree_nodes.xml"])
    used: set[str] = set()
    for tree in NAV2_TREES:
        for mission in import_files([tree], model).values():
            text = write_missions({mission["name"]: mission}, tmp_path / tree.stem, tree.name)[0]
            used |= {n.plugin for n in walk(read_mission(text).root) if isinstance(n, PluginNode)}
    assert used == {
        "RoundRobin",
        "DistanceController",
        "SpeedController",
        "GoalUpdater",
        "GoalUpdatedController",
        "PathLongerOnApproach",
    }


def test_a_model_declared_node_without_a_plugin_is_named_still_to_write(tmp_path: Path) -> None:
    (tmp_path / "model.xml").write_text("""<root BTCPP_format="4"><TreeNodesModel>
      <Decorator ID="BatteryGuard"><input_port name="level" type="double"/></Decorator>
      <Action ID="Dock"/></TreeNodesModel></root>""")
    (tmp_path / "t.xml").write_text("""<root BTCPP_format="4"><BehaviorTree ID="T">
      <BatteryGuard level="0.2"><Dock/></BatteryGuard></BehaviorTree></root>""")
    model = read_node_model([tmp_path / "model.xml"])
    paths = write_missions(import_files([tmp_path / "t.xml"], model), tmp_path / "out", "t.xml")
    library = TreeLibrary(model.resolver(), STANDARD_BEHAVIOURS, model.plugins(node_plugins()))
    assert check_files(paths, library=library) == []
    assert unwritten_plugins(library, paths) == ["BatteryGuard (decorator)"]


def test_a_model_port_without_a_default_is_optional(tmp_path: Path) -> None:
    model = read_node_model([NAV2 / "nav2_tree_nodes.xml"])
    signature = model["ComputePathToPose"].signature()
    assert repr(signature.parameters["start"].default) == "unset"


@pytest.mark.parametrize(
    "text, ctype, value",
    [
        ("numeric_limits<double>::infinity()", "double", math.inf),  # Nav2 rolling's model writes this
        ("-std::numeric_limits<double>::infinity()", "double", -math.inf),
        ("std::numeric_limits<float>::max()", "double", sys.float_info.max),
        ("std::numeric_limits<int>::max()", "int", 2**31 - 1),
        ("std::numeric_limits<uint16_t>::max()", "unsigned int", 2**16 - 1),
        ("inf", "double", math.inf),  # as std::stod reads it
    ],
)
def test_a_model_default_may_be_a_cpp_numeric_limit(text: str, ctype: str, value: float) -> None:
    assert convert_literal(text, ctype) == value


def test_a_model_default_of_the_wrong_type_is_located(tmp_path: Path) -> None:
    (tmp_path / "model.xml").write_text("""<root BTCPP_format="4"><TreeNodesModel>
      <Action ID="Drive">
        <input_port name="speed" type="double" default="fast"/></Action></TreeNodesModel></root>""")
    model = read_node_model([tmp_path / "model.xml"])
    with pytest.raises(
        BtXmlError,
        match=r"model.xml:3:9: the default of port 'speed' of node 'Drive': 'fast' is not "
        r"a number",
    ):
        model["Drive"].signature()  # what checking a tree that calls Drive asks for


def test_the_actor_demo_imports_as_one_pytwb_workbench(tmp_path: Path) -> None:
    missions = import_files([PYTWB], dialect="pytwb")
    assert sorted(missions) == sorted(p.stem for p in PYTWB.glob("*.xml"))  # named after their files
    paths = write_missions(missions, tmp_path, "pytwb_actor_demo")
    assert check_files(paths, library=TreeLibrary(None, STANDARD_BEHAVIOURS)) == []
    calls = {n.actor for n in walk(read_mission(tmp_path / "bt_pick.yaml").root) if hasattr(n, "actor")}
    assert {"bt_search", "bt_catch"} <= calls
    assert {"bt_search", "test_catch"} <= {
        n.actor for n in walk(read_mission(tmp_path / "test_pp.yaml").root) if hasattr(n, "actor")
    }


def test_the_workbench_says_which_leaf_actors_are_missing(tmp_path: Path) -> None:
    from bt_engine.trees.testing import FakeResolver

    paths = write_missions(import_files([PYTWB], dialect="pytwb"), tmp_path, "pytwb_actor_demo")
    errors = check_files(paths, library=TreeLibrary(FakeResolver(), STANDARD_BEHAVIOURS))
    missing = {str(e).split("unknown actor '")[1].split("'")[0] for e in errors if "unknown actor" in str(e)}
    assert {"GoToPose", "Watch", "SetLocations", "LookForCoke", "Pick", "Place"} <= missing
    assert not missing & {"bt_search", "bt_catch", "bt_carry", "test_catch"}  # the trees call each other


PLUGGED = """\
name: plugged
inputs: {goal: {type: dict, default: {x: 1.0}}}
outputs: [current]
root:
  control: RoundRobin
  children:
    - decorator: GoalUpdater
      with: {input_goal: "{goal}"}
      out: {output_goal: current}
      child:
        decorator: DistanceController
        with: {distance: 2.5}
        child: {wait: 1}
    - decorator: GoalUpdatedController
      child: {wait: 2}
"""


def test_plugins_round_trip_through_xml(tmp_path: Path) -> None:
    library = TreeLibrary(None, STANDARD_BEHAVIOURS)
    library.add(parse_mission(PLUGGED, "plugged.yaml"))
    xml = tmp_path / "plugged.xml"
    from bt_xml import export_tree

    xml.write_text(export_tree("plugged", library))
    text = xml.read_text()
    assert '<Control ID="RoundRobin"' in text and '<Decorator ID="DistanceController"' in text
    assert '<GoalUpdater input_goal="{goal}" output_goal="{current}">' in text
    back = import_files([xml])["plugged"]
    paths = write_missions({"plugged": back}, tmp_path / "back", "plugged.xml")
    assert mission_differences(library["plugged"], read_mission(paths[0])) == []
    assert check_files(paths, library=TreeLibrary(None, STANDARD_BEHAVIOURS)) == []
    assert Exporter  # the class the CLI uses
