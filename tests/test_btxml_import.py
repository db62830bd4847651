"""BehaviorTree.CPP and pytwb XML imported as missions: converted, written, checked
(against a node model) and run against small actors (tests/data/btxml/)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bt_engine import Runtime, SubSystem, actor
from bt_xml import import_files, read_node_model, write_missions
from bt_engine.trees import STANDARD_BEHAVIOURS, TreeHost, TreeLibrary, check_files, read_mission

DATA = Path(__file__).parent / "data" / "btxml"


def convert(tmp_path: Path, *files: str, nodes: str | None = None, dialect: str = "btcpp") -> list[Path]:
    model = read_node_model([DATA / nodes]) if nodes else None
    missions = import_files([DATA / f for f in files], model, dialect=dialect)
    return write_missions(missions, tmp_path, ", ".join(files))


# ---------------------------------------------------------------- Nav2-shaped navigator


class Nav2Actors(SubSystem):
    """Stand-ins for Nav2's BT nodes: planning fails once, following takes 2.5 s."""

    def __init__(self) -> None:
        super().__init__()
        self.calls: list[str] = []

    @actor("ComputePathToPose")
    def compute_path(self, goal: dict, planner_id: str = "GridBased") -> list:
        self.calls.append("plan")
        if self.calls.count("plan") == 1:
            raise RuntimeError("no valid path")
        return [[0.0, 0.0], [goal["x"], goal["y"]]]

    @actor("FollowPath")
    def follow_path(self, path: list, controller_id: str = "FollowPath", goal_checker_id: str = "goal_checker") -> None:
        self.calls.append("follow")
        self.runtime.sleep(2.5)

    @actor("ClearEntireCostmap")
    def clear(self, service_name: str) -> None:
        self.calls.append("clear " + service_name.split("/")[0])

    @actor("GoalUpdated")
    def goal_updated(self) -> bool:
        return False

    @actor("Spin")
    def spin(self, spin_dist: float = 1.57) -> None:
        self.calls.append("spin")

    @actor("Wait")
    def wait(self, wait_duration: float = 1.0) -> None:
        self.runtime.sleep(wait_duration)

    @actor("BackUp")
    def back_up(self, backup_dist: float = 0.15, backup_speed: float = 0.025) -> None:
        self.calls.append("backup")


def test_nav2_navigator_converts_to_the_mapped_controls(tmp_path: Path) -> None:
    paths = convert(tmp_path, "nav2_navigate.xml", nodes="nav2_nodes.xml")
    assert [p.name for p in paths] == ["RecoveryActions.yaml", "NavigateWithReplanning.yaml"]  # the include first
    mission = read_mission(tmp_path / "NavigateWithReplanning.yaml")
    assert [i.name for i in mission.inputs] == ["goal"]
    assert [o.name for o in mission.outputs] == ["path"]
    text = (tmp_path / "NavigateWithReplanning.yaml").read_text()
    for kind in ("recovery:", "pipeline_sequence:", "rate_controller:", "retries: 6", "hz: 1.0", "do: RecoveryActions"):
        assert kind in text


def test_nav2_navigator_checks_against_the_node_model_without_nav2(tmp_path: Path) -> None:
    paths = convert(tmp_path, "nav2_navigate.xml", nodes="nav2_nodes.xml")
    resolver = read_node_model([DATA / "nav2_nodes.xml"]).resolver()
    assert check_files(paths, library=TreeLibrary(resolver, STANDARD_BEHAVIOURS)) == []
    # a port the model does not declare is an error, at its place in the YAML
    broken = tmp_path / "NavigateWithReplanning.yaml"
    broken.write_text(broken.read_text().replace("controller_id: FollowPath", "controler_id: FollowPath"))
    errors = check_files(paths, library=TreeLibrary(resolver, STANDARD_BEHAVIOURS))
    assert len(errors) == 1 and "has no parameter 'controler_id' (did you mean 'controller_id'?)" in str(errors[0])


def test_nav2_navigator_runs_replanning_and_recovering(rt: Runtime, tmp_path: Path) -> None:
    convert(tmp_path, "nav2_navigate.xml", nodes="nav2_nodes.xml")
    nav = rt.add_subsystem("nav", Nav2Actors)
    TreeHost(rt).load_folder(tmp_path)
    result = rt.call("NavigateWithReplanning", goal={"x": 2.0, "y": 1.0})
    assert result == {"path": [[0.0, 0.0], [2.0, 1.0]]}
    assert nav.calls[:3] == ["plan", "clear global_costmap", "plan"]  # planning failed once, recovered
    assert nav.calls.count("plan") >= 3  # replanned at 1 Hz while following
    assert "spin" not in nav.calls
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_nav2_recovery_subtree_runs_to_its_end_under_its_reactive_guard(rt: Runtime, tmp_path: Path) -> None:
    # GoalUpdated is a Condition in the node model: it becomes a condition leaf, which
    # answers within the tick, so the ReactiveFallback re-asks it without halting the
    # recovery sequence behind it (a do: leaf would restart it on every tick)
    convert(tmp_path, "nav2_navigate.xml", nodes="nav2_nodes.xml")
    assert "condition: GoalUpdated" in (tmp_path / "RecoveryActions.yaml").read_text()
    nav = rt.add_subsystem("nav", Nav2Actors)
    TreeHost(rt, max_period=0.1).load_folder(tmp_path)
    rt.call("RecoveryActions")
    assert nav.calls == ["clear local_costmap", "clear global_costmap", "spin", "backup"]
    assert rt.now() == pytest.approx(5.0)  # the 5 s Wait ran whole, re-guarded every 0.1 s
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_a_long_form_condition_is_a_condition_leaf(tmp_path: Path) -> None:
    xml = tmp_path / "guard.xml"
    xml.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Guard"><ReactiveSequence>'
        '<Condition ID="BatteryOk"/><Action ID="Patrol"/>'
        "</ReactiveSequence></BehaviorTree></root>"
    )
    [path] = write_missions(import_files([xml], None), tmp_path / "out", "guard.xml")
    text = path.read_text()
    assert "condition: BatteryOk" in text and "do: Patrol" in text


# ---------------------------------------------------------------- tutorial-shaped trees


class TutorialActors(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.said: list[str] = []
        self.opened = 0

    @actor("MoveTo")
    def move_to(self, goal: str) -> None:
        self.said.append(f"move to {goal}")
        self.runtime.sleep(1.0)

    @actor("Say")
    def say(self, text: str) -> None:
        self.said.append(text)

    @actor("OpenDoor")
    def open_door(self) -> bool:
        self.opened += 1
        return False  # locked

    @actor("PickLock")
    def pick_lock(self) -> None:
        self.runtime.sleep(1.5)


def test_tutorial_trees_convert_subtree_ports_scripts_and_conditions(tmp_path: Path) -> None:
    convert(tmp_path, "tutorial.xml")
    main = read_mission(tmp_path / "MainTree.yaml")
    assert main.inputs == ()  # it writes every key it reads first
    door = read_mission(tmp_path / "DoorClosed.yaml")
    assert [(i.name, i.required) for i in door.inputs] == [("door", False)]
    assert [o.name for o in door.outputs] == ["door", "tries"]
    report = read_mission(tmp_path / "Report.yaml")
    assert [(i.name, i.required) for i in report.inputs] == [("target", True), ("door_open", True)]
    text = (tmp_path / "MainTree.yaml").read_text()
    assert 'check: door_open and reported == "yes"' in text  # && translated
    assert "check: not door_open" in text  # _skipIf="!door_open"
    assert "{_DoorClosed_out1.tries}" in text  # tries="{attempts}" written back
    assert "{do: Report, with: {target: '{target}', door_open: '{door_open}'}" in text  # _autoremap


def test_tutorial_trees_run(rt: Runtime, tmp_path: Path) -> None:
    convert(tmp_path, "tutorial.xml")
    tut = rt.add_subsystem("tutorial", TutorialActors)
    TreeHost(rt).load_folder(tmp_path)
    result = rt.call("MainTree")
    assert result == {
        "door_open": True,
        "attempts": 5,
        "greeting": "hello",
        "target": "kitchen",
        "arrived": True,
        "reported": "yes",
    }
    assert tut.opened == 3  # RetryUntilSuccessful num_attempts="3"
    assert tut.said[:4] == ["move to kitchen", "kitchen", "again", "again"]
    assert sorted(tut.said[4:6]) == ["a", "b"] and tut.said[6:] == ["done"]
    assert rt.now() == pytest.approx(1.5 + 1.0 + 0.5 + 0.25)  # pick lock, move, Sleep, Delay


# ---------------------------------------------------------------- pytwb


class PytwbActors(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.log: list[Any] = []

    @actor("Undock")
    def undock(self, speed: float) -> bool:
        self.log.append(("undock", speed))
        return len(self.log) > 1  # fails once: Retry num_failures="[3]"

    @actor("GoTo")
    def go_to(self, room: str) -> None:
        self.log.append(("goto", room))
        self.runtime.sleep(1.0)

    @actor("Dock")
    def dock(self, station: str, options: dict) -> None:
        self.log.append(("dock", station, options))
        self.runtime.sleep(2.0)


def test_pytwb_trees_convert_and_run(rt: Runtime, tmp_path: Path) -> None:
    paths = convert(tmp_path, "pytwb_patrol.xml", dialect="pytwb")
    assert [p.name for p in paths] == ["patrol.yaml", "visit_rooms.yaml"]
    text = (tmp_path / "patrol.yaml").read_text()
    assert "policy: success_on_one" in text and "times: 3" in text
    log = rt.add_subsystem("robot", PytwbActors).log
    TreeHost(rt).load_folder(tmp_path)
    assert rt.call("patrol", station="dock_a") == {}
    assert log[:2] == [("undock", 0.2), ("undock", 0.2)]
    # the kitchen succeeds, so the inverter fails and the hall runs
    assert log[2:6] == [("goto", "kitchen"), ("goto", "hall"), ("goto", "kitchen"), ("goto", "hall")]
    assert log[6] == ("dock", "dock_a", {"slow": True, "tries": 2})


def test_every_converted_tree_checks_with_a_structure_only_library(tmp_path: Path) -> None:
    for files, dialect in ((("tutorial.xml",), "btcpp"), (("pytwb_patrol.xml",), "pytwb")):
        out = tmp_path / files[0]
        paths = convert(out, *files, dialect=dialect)
        assert check_files(paths, library=TreeLibrary(None, STANDARD_BEHAVIOURS)) == []
