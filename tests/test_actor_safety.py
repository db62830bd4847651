"""What actors declare about motion (``@actor(moves=, read_only=, limits=)``), how the
catalog exports it, and how a tree's flags follow from the actors it calls."""
from __future__ import annotations

import inspect

import pytest

from bt_engine import Runtime, Safety, SubSystem, actor
from bt_engine.catalog import text_lines, tool_schema
from bt_engine.cli.actor_index import ActorEntry, ActorIndex
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


def test_declarations_reach_the_ref_and_the_catalog(rt):
    rt.add_subsystem("base", Base)
    walk = tool_schema(rt.resolve("base.roll"))
    assert (walk["moves"], walk["read_only"]) == (True, False)
    assert walk["parameters"]["properties"]["speed"] == {"type": "number", "default": 0.1,
                                                          "minimum": 0.0, "maximum": 0.26}
    assert walk["parameters"]["properties"]["distance"]["minimum"] == -1.0
    joints = tool_schema(rt.resolve("base.joints"))["parameters"]["properties"]["q"]
    assert joints["items"] == {"type": "number", "minimum": -3.0, "maximum": 3.0}
    assert tool_schema(rt.resolve("base.pose"))["read_only"] is True
    assert (rt.resolve("base.remember").moves, rt.resolve("base.remember").read_only) == (False, False)
    assert rt.resolve("base.cmd_vel").moves is True       # a publisher that commands motion
    assert rt.resolve("base.odom").read_only is True      # listening changes nothing
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
    flags = {name: (rt.resolve(name).moves, rt.resolve(name).read_only)
             for name in ("drive_and_look", "look", "outer", "store")}
    assert flags == {"drive_and_look": (True, False), "look": (False, True),
                     "outer": (True, False), "store": (False, False)}
    assert tool_schema(rt.resolve("outer"))["moves"] is True


def test_the_actor_index_keeps_the_flags_for_trees_checked_without_a_runtime(rt, tmp_path):
    rt.add_subsystem("base", Base)
    index = ActorIndex.of(rt.root.all_actors())
    index.save(tmp_path / "actors.json", {"base": "x:Base"}, {})
    loaded = ActorIndex.load(tmp_path / "actors.json", {"base": "x:Base"})
    assert loaded is not None
    assert loaded.resolve("base.roll").safety == Safety(moves=True)
    library = TreeLibrary(loaded.resolve)
    mission = parse_mission(TREES["drive_and_look.yaml"])
    library.add(mission)
    assert mission_safety(mission, library.resolve).moves is True
