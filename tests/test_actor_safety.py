"""What actors declare about motion (``@actor(moves=, read_only=, limits=)``), how the
catalog exports it, and how a tree's flags follow from the actors it calls."""

from __future__ import annotations

from typing import Literal

import pytest

from bt_engine import Safety, SubSystem, actor
from bt_engine.catalog import text_lines, tool_schema
from bt_cli.actor_index import ActorIndex
from bt_engine.trees import TreeLibrary, parse_mission, register_tree_folder
from bt_engine.trees._safety import mission_safety


class Base(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.register_publisher("cmd_vel", dict, "/cmd_vel", moves=True)
        self.register_subscriber("odom", dict, "/odom")

    @actor(moves=True, limits={"distance": (-1.0, 1.0), "speed": (0.0, 0.26)})
    def roll(self, distance: float, speed: float = 0.1) -> float:
        """Drive straight."""
        return distance

    @actor(moves=True, limits={"q": (-3.0, 3.0)})
    def joints(self, *q: float) -> list[float]:
        """Move the arm."""
        return list(q)

    @actor(read_only=True)
    def pose(self) -> float:
        """Where it is."""
        return 0.0

    @actor
    def remember(self, x: float) -> None:
        """Store x (neither moving nor read-only)."""

    @actor
    def light(self, colour: Literal["red", "green"] = "red") -> None:
        """Switch the light on."""


def test_declarations_reach_the_ref_and_the_catalog(rt):
    rt.add_subsystem("base", Base)
    walk = tool_schema(rt.resolve("base.roll"))
    assert (walk["moves"], walk["read_only"]) == (True, False)
    assert walk["parameters"]["properties"]["speed"] == {
        "type": "number",
        "default": 0.1,
        "minimum": 0.0,
        "maximum": 0.26,
    }
    assert walk["parameters"]["properties"]["distance"]["minimum"] == -1.0
    joints = tool_schema(rt.resolve("base.joints"))["parameters"]["properties"]["q"]
    assert joints["items"] == {"type": "number", "minimum": -3.0, "maximum": 3.0}
    assert tool_schema(rt.resolve("base.pose"))["read_only"] is True
    assert (rt.resolve("base.remember").moves, rt.resolve("base.remember").read_only) == (False, False)
    assert rt.resolve("base.cmd_vel").moves is True  # a publisher that commands motion
    assert rt.resolve("base.odom").read_only is True  # listening changes nothing
    assert rt.resolve("sleep").read_only is True
    lines = text_lines(rt.resolve("base.roll").doc, walk)
    assert "Moves the robot." in lines and "  speed (number, 0.0 to 0.26, default 0.1)" in lines


def test_bad_declarations_fail_where_they_are_written():
    with pytest.raises(TypeError, match="no parameter 'sped'"):

        @actor(limits={"sped": (0.0, 1.0)})
        def walk(speed: float) -> None: ...

    with pytest.raises(TypeError, match="low 2 above high 1"):

        @actor(limits={"speed": (2, 1)})
        def walk2(speed: float) -> None: ...

    with pytest.raises(TypeError, match="not read-only"):
        actor(moves=True, read_only=True)


TREES = {
    "drive_and_look.yaml": "name: drive_and_look\nroot:\n  sequence:\n    - do: base.roll\n"
    "      with: {distance: 0.5}\n    - do: base.pose\n",
    "look.yaml": "name: look\nroot:\n  sequence:\n    - do: base.pose\n    - wait: 1\n",
    "outer.yaml": "name: outer\nroot:\n  sequence:\n    - do: look\n    - do: drive_and_look\n",
    "store.yaml": "name: store\nroot:\n  do: base.remember\n  with: {x: 1.0}\n",
}


def test_a_tree_moves_when_an_actor_it_calls_does_transitively(rt, tmp_path):
    rt.add_subsystem("base", Base)
    for name, text in TREES.items():
        (tmp_path / name).write_text(text)
    register_tree_folder(rt, tmp_path)
    flags = {
        name: (rt.resolve(name).moves, rt.resolve(name).read_only)
        for name in ("drive_and_look", "look", "outer", "store")
    }
    assert flags == {
        "drive_and_look": (True, False),
        "look": (False, True),
        "outer": (True, False),
        "store": (False, False),
    }
    assert tool_schema(rt.resolve("outer"))["moves"] is True


def test_the_actor_index_keeps_the_flags_for_trees_checked_without_a_runtime(rt, tmp_path):
    rt.add_subsystem("base", Base)
    index = ActorIndex.of(rt.root.all_actors())
    index.save(tmp_path / "actors.json", {"base": "x:Base"}, {})
    loaded = ActorIndex.load(tmp_path / "actors.json", {"base": "x:Base"})
    assert loaded is not None
    assert loaded.resolve("base.roll").safety == Safety(
        moves=True, limits={"distance": (-1.0, 1.0), "speed": (0.0, 0.26)}
    )
    library = TreeLibrary(loaded.resolve)
    mission = parse_mission(TREES["drive_and_look.yaml"])
    library.add(mission)
    assert mission_safety(mission, library.resolve).moves is True


def _problems(resolver, text: str) -> list[str]:
    library = TreeLibrary(resolver)
    library.add(parse_mission(text, "m.yaml"), strict=False)
    return [str(e) for e in library.validate()]


@pytest.mark.parametrize("source", ["runtime", "index"])
def test_a_mission_outside_an_actors_declared_range_fails_at_load_where_it_is_written(rt, tmp_path, source):
    """As MCP refuses such a call, `check`, `run` and serve refuse the mission."""
    rt.add_subsystem("base", Base)
    resolver = rt.root.resolve
    if source == "index":
        ActorIndex.of(rt.root.all_actors()).save(tmp_path / "a.json", {"base": "x:Base"}, {})
        resolver = ActorIndex.load(tmp_path / "a.json", {"base": "x:Base"}).resolve
    bad = (
        "name: m\nroot:\n  sequence:\n    - do: base.roll\n      with: {distance: 0.5, speed: 0.3}\n"
        "    - do: base.joints\n      with: [0.0, 3.5]\n"
        "    - do: base.light\n      with: {colour: blue}\n"
    )
    assert _problems(resolver, bad) == [
        "m.yaml:5:36: argument 'speed' of actor 'base.roll' is 0.3, expected a value within 0.0..0.26 "
        "(the actor's declared range)",
        "m.yaml:7:19: argument 'q' of actor 'base.joints' is 3.5, expected a value within -3.0..3.0 "
        "(the actor's declared range)",
        "m.yaml:9:22: argument 'colour' of actor 'base.light' is 'blue', expected one of 'red', 'green'",
    ]
    good = (
        "name: m\ninputs: {s: {type: float, default: 0.5}}\nroot:\n  sequence:\n"
        "    - do: base.roll\n      with: {distance: -1.0, speed: 0.26}\n"
        # a reference: its value is known when the tree runs
        '    - do: base.roll\n      with: {distance: "{s}"}\n'
        "    - do: base.light\n      with: {colour: green}\n"
    )
    assert _problems(resolver, good) == []


def test_a_value_read_from_the_blackboard_outside_the_range_fails_its_node_when_called(rt, tmp_path):
    rt.add_subsystem("base", Base)
    (tmp_path / "far.yaml").write_text(
        'name: far\ninputs: {d: {type: float, default: 0.5}}\nroot:\n  do: base.roll\n  with: {distance: "{d}"}\n'
    )
    register_tree_folder(rt, tmp_path)
    assert rt.call("far") == {}
    with pytest.raises(
        Exception,
        match=r"argument 'distance' of actor 'base.roll' is 2.0, expected a value "
        r"within -1.0..1.0 \(the actor's declared range\)",
    ):
        rt.call("far", d=2.0)
