"""The catalog and its JSON-Schema export."""

from __future__ import annotations

import json
import pathlib
from typing import Iterator, Optional

import pytest

from bt_engine import Runtime, SubSystem, actor, param_docs
from bt_engine.catalog import catalog, doc_problems, text_lines, tool_schema, tool_schemas
from bt_cli.actor_index import INDEX_VERSION, ActorIndex
from bt_cli.config import import_object, load_config
from bt_engine.trees import register_tree_folder


class Nav(SubSystem):
    @actor
    def goto(self, x: float, y: float, theta: float = 0.0, frame: str = "map") -> bool:
        """Drive to (x, y, theta) in the map frame.

        Longer explanation that the summary leaves out."""
        return True

    @actor("watch", "multi")
    def watch(self, emit, labels: list[str], limit: Optional[int] = None):
        """Stream detections."""
        return lambda: None


def test_catalog_lists_path_doc_signature_kind(rt):
    rt.add_subsystem("nav", Nav)
    entries = {e["path"]: e for e in catalog(rt.root)}
    assert entries["nav.goto"]["kind"] == "sync"
    assert entries["nav.watch"]["kind"] == "multi"
    assert entries["nav.goto"]["signature"].startswith("nav.goto(x: float, y: float")
    assert entries["nav.goto"]["doc"].startswith("Drive to")
    assert "sleep" in entries


def test_json_schema_tools(rt):
    rt.add_subsystem("nav", Nav)
    tools = {t["name"]: t for t in tool_schemas(rt.root)}
    goto = tools["nav.goto"]
    assert goto["description"] == "Drive to (x, y, theta) in the map frame."
    assert goto["parameters"] == {
        "type": "object",
        "properties": {
            "x": {"type": "number"},
            "y": {"type": "number"},
            "theta": {"type": "number", "default": 0.0},
            "frame": {"type": "string", "default": "map"},
        },
        "required": ["x", "y"],
    }
    watch = tools["nav.watch"]["parameters"]
    assert watch["properties"]["labels"] == {"type": "array", "items": {"type": "string"}}
    assert watch["properties"]["limit"]["anyOf"] == [{"type": "integer"}, {"type": "null"}]
    assert watch["required"] == ["labels"]


# -- parameter docs (the Args: convention) --------------------------------------------------
class Documented(SubSystem):
    @actor
    def goto(
        self, x: float, y: float, theta=0.0, frame: str = "map", timeout: float | None = None
    ) -> tuple[float, float, float]:
        """Drive to (x, y) in the map frame.

        Fails when no path exists.

        Args:
            x: goal x [m]
            y: goal y [m]
            theta: heading at the goal [rad]
            frame: the goal's frame
            timeout: give up after this long [s]

        Returns:
            the pose reached: x [m], y [m], yaw [rad]
        """
        return (x, y, theta)

    @actor
    def move_joint(self, *q: float) -> list[float]:
        """Move the joints.

        Args:
            *q: joint positions [rad]
        """
        return list(q)

    @actor
    @param_docs(speed="top speed [m/s]", distance="how far [m]")
    def stroll(self, distance: float, speed: float = 0.1) -> float:
        """Walk straight.

        Args:
            distance: overridden by param_docs
        """
        return distance

    @param_docs(seconds="how long [s]")
    @actor("nap", "async")
    def nap(self, done, seconds: float) -> None:
        """Nap (the decorators in the other order)."""
        done(None)

    @actor
    def frames(self, period: float = 1.0) -> Iterator[dict]:
        """Stream frames.

        Args:
            period: between frames [s]
        """
        yield {}

    @actor
    def publish(self, msg: Msg) -> None:
        """Publish.

        Args:
            msg: the message to send
        """


class Msg:
    pass


def _tools(rt) -> dict:
    rt.add_subsystem("d", Documented)
    return {t["name"]: t for t in tool_schemas(rt.root)}


def test_every_parameter_gets_description_type_unit_and_default(rt):
    goto = _tools(rt)["d.goto"]
    assert goto["description"] == "Drive to (x, y) in the map frame."
    assert goto["details"] == "Fails when no path exists."
    assert goto["parameters"] == {
        "type": "object",
        "properties": {
            "x": {"type": "number", "description": "goal x [m]", "unit": "m"},
            "y": {"type": "number", "description": "goal y [m]", "unit": "m"},
            "theta": {
                "type": "number",
                "description": "heading at the goal [rad]",
                "unit": "rad",
                "default": 0.0,
            },  # no hint: the type of the default
            "frame": {"type": "string", "description": "the goal's frame", "default": "map"},
            "timeout": {
                "anyOf": [{"type": "number"}, {"type": "null"}],
                "description": "give up after this long [s]",
                "unit": "s",
                "default": None,
            },
        },
        "required": ["x", "y"],
    }
    assert goto["returns"] == {
        "type": "array",
        "items": {"type": "number"},
        "description": "the pose reached: x [m], y [m], yaw [rad]",
    }


def test_variadic_explicit_stream_and_class_typed_parameters(rt):
    tools = _tools(rt)
    q = tools["d.move_joint"]["parameters"]["properties"]["q"]
    assert q == {
        "type": "array",
        "items": {"type": "number"},
        "unit": "rad",
        "description": "joint positions [rad] (positional values, *q)",
    }
    stroll = tools["d.stroll"]["parameters"]["properties"]
    assert stroll["distance"]["description"] == "how far [m]"  # param_docs wins over the docstring
    assert stroll["speed"] == {"type": "number", "description": "top speed [m/s]", "unit": "m/s", "default": 0.1}
    assert tools["d.nap"]["parameters"]["properties"]["seconds"]["description"] == "how long [s]"
    frames = tools["d.frames"]
    assert frames["returns"] == {"type": "object"}  # a stream: each value
    assert "details" not in frames
    msg = tools["d.publish"]["parameters"]["properties"]["msg"]
    assert msg == {"type": "object", "description": f"the message to send ({__name__}.Msg)"}


def test_doc_problems_names_undocumented_and_unknown_parameters(rt):
    class Sloppy(SubSystem):
        @actor
        def f(self, a: int, b: int) -> None:
            """F.

            Args:
                a: documented
                c: a typo
            """

    rt.add_subsystem("s", Sloppy)
    assert doc_problems(rt.resolve("s.f")) == [
        "s.f: parameter 'b' has no description",
        "s.f: documents 'c', which is no parameter",
    ]
    rt.add_subsystem("d", Documented)
    assert [p for r in rt.root.all_actors() if r.path.startswith("d.") for p in doc_problems(r)] == []


def test_text_lines_show_one_line_per_parameter(rt):
    tools = _tools(rt)
    lines = text_lines(rt.resolve("d.goto").doc, tools["d.goto"])
    assert lines == [
        "Drive to (x, y) in the map frame.",
        "",
        "Fails when no path exists.",
        "Args:",
        "  x: goal x [m] (number, required)",
        "  y: goal y [m] (number, required)",
        "  theta: heading at the goal [rad] (number, default 0.0)",
        "  frame: the goal's frame (string, default 'map')",
        "  timeout: give up after this long [s] (number or null, default None)",
        "Returns: the pose reached: x [m], y [m], yaw [rad] (array of number)",
    ]
    assert (
        text_lines(rt.resolve("d.move_joint").doc, tools["d.move_joint"])[-1]
        == "  *q: joint positions [rad] (array of number)"
    )
    assert text_lines("", tools["sleep"])[0] == "(no docstring)"


# -- trees ----------------------------------------------------------------------------------
TREE = """\
name: fetch
doc: Fetch something.
inputs:
  room: {type: str, default: kitchen, doc: where to go}
  seconds: {type: float, default: 2.0, doc: "how long to drive [s]"}
  spot: {type: list, doc: "x, y in the map frame [m]"}
  anything: {doc: "no type given"}
outputs:
  photo: {type: dict, doc: "what was seen"}
  distance: {type: float, doc: "how far it drove [m]"}
  plain: str
root:
  sequence:
    - {do: sleep, with: {seconds: "{seconds}"}}
    - set: {photo: {room: "{room}"}, distance: 1.0, plain: ok}
"""


def test_tree_inputs_and_outputs_are_described(rt, tmp_path):
    (tmp_path / "fetch.yaml").write_text(TREE)
    register_tree_folder(rt, tmp_path)
    tool = tool_schema(rt.resolve("fetch"))
    assert tool["description"] == "Fetch something."
    assert tool["is_tree"] is True
    assert tool["parameters"] == {
        "type": "object",
        "properties": {
            "room": {"type": "string", "description": "where to go", "default": "kitchen"},
            "seconds": {"type": "number", "description": "how long to drive [s]", "unit": "s", "default": 2.0},
            "spot": {"type": "array", "description": "x, y in the map frame [m]", "unit": "m"},
            "anything": {"description": "no type given"},
        },
        "required": ["spot", "anything"],
    }
    assert tool["returns"] == {
        "type": "object",
        "description": "the outputs (null: not written in this run)",
        "properties": {
            "photo": {"type": "object", "description": "what was seen"},
            "distance": {"type": "number", "description": "how far it drove [m]", "unit": "m"},
            "plain": {"type": "string"},
        },
    }
    lines = text_lines(rt.resolve("fetch").doc, tool)
    assert lines[1:3] == ["Inputs:", "  room: where to go (string, default 'kitchen')"]
    assert lines[-4:] == [
        "Outputs:",
        "  photo: what was seen (object)",
        "  distance: how far it drove [m] (number)",
        "  plain (string)",
    ]


# -- the project's real configuration: what `actorbt catalog --json` shows ------------------
REPO = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def project_catalog():
    """Every actor and tree of actorbt.yaml, as ActorEntry (what the index stores), built
    like `actorbt catalog` builds it but without touching the project's .actorbt/."""
    cfg = load_config(REPO / "actorbt.yaml")
    with Runtime(clock="virtual") as runtime:
        for name, spec in cfg.subsystems.items():
            runtime.add_subsystem(name, import_object(spec, name))
        register_tree_folder(runtime, cfg.trees_dir())
        refs = runtime.root.all_actors()
        entries = ActorIndex.of(refs).entries
        problems = [p for r in refs for p in doc_problems(r)]
    return entries, problems


def _documented(entries, wanted):
    bad = []
    for e in entries:
        if wanted(e.path):
            for name, schema in e.tool["parameters"]["properties"].items():
                if not schema.get("description", "").strip():
                    bad.append(f"{e.path}: {name} has no description")
                if not ({"type", "anyOf", "enum"} & set(schema)):
                    bad.append(f"{e.path}: {name} has no type")
    return bad


def test_every_parameter_of_the_project_has_a_description_and_a_type(project_catalog):
    entries, problems = project_catalog
    assert len(entries) > 40
    assert _documented(entries, lambda p: True) == []
    assert problems == []  # Args: entries match the parameters (no typos)


def test_the_project_catalog_shows_units_and_tree_input_docs(project_catalog):
    entries, _ = project_catalog
    tools = {e.path: e.tool for e in entries}
    x = tools["robot.navigation.goto"]["parameters"]["properties"]["x"]
    assert x == {"type": "number", "description": "goal x in the map frame [m]", "unit": "m"}
    assert tools["robot.navigation.goto"]["parameters"]["properties"]["timeout"]["unit"] == "s"
    place = tools["bt_pick_place"]["parameters"]["properties"]["place"]
    assert place["type"] == "object" and place["unit"] == "m"
    assert place["description"].startswith("the place surface")
    assert place["default"] == {"x": 7.0, "y": 6.2, "size_x": 0.6, "size_y": 0.4, "height": 0.12}
    assert tools["bt_pick_place"]["parameters"]["properties"]["category"]["description"] == "can, bottle, or any"
    assert set(tools["bt_pick_place"]["returns"]["properties"]) == {"found", "grasp", "placed"}
    assert tools["demo_patrol"]["parameters"]["properties"]["pause"]["unit"] == "s"


def test_the_actor_index_keeps_the_descriptions(project_catalog, tmp_path):
    entries, _ = project_catalog
    index = ActorIndex([e for e in entries if not e.is_tree])
    path = tmp_path / "actors.json"
    index.save(path, {"robot": "actors.robot:Robot"}, {})
    data = json.loads(path.read_text())
    assert data["version"] == INDEX_VERSION >= 2
    loaded = ActorIndex.load(path, {"robot": "actors.robot:Robot"})
    goto = loaded.resolve("robot.navigation.goto")
    assert goto.tool == index.resolve("robot.navigation.goto").tool
    assert "  x: goal x in the map frame [m] (number, required)" in goto.text_lines()
    data["version"] = 1  # a cache from before the descriptions is rebuilt
    path.write_text(json.dumps(data))
    assert ActorIndex.load(path, {"robot": "actors.robot:Robot"}) is None
