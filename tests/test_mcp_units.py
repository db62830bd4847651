"""The MCP server's parts without a session: argument checks, tool descriptions,
settings, and the service in-process (what a call does, in which order)."""

from __future__ import annotations

import inspect
import pathlib

import anyio
import pytest

from bt_engine import Runtime
from bt_cli.config import ConfigError
from bt_mcp.service import ToolService
from bt_mcp.settings import McpSettings
from bt_mcp.tools import input_schema, mcp_tool
from bt_mcp.validate import argument_errors, call_arguments
from bt_engine.trees import register_tree_folder

FIXTURE = pathlib.Path(__file__).resolve().parent / "fixtures" / "mcp"

SCHEMA = {
    "type": "object",
    "additionalProperties": False,
    "required": ["distance"],
    "properties": {
        "distance": {"type": "number", "description": "how far [m]", "minimum": -1, "maximum": 1},
        "speed": {"type": "number", "minimum": 0, "maximum": 0.26},
        "q": {"type": "array", "items": {"type": "number", "maximum": 3}},
    },
}


def test_every_problem_names_its_argument():
    assert argument_errors(SCHEMA, {"distance": 0.5, "speed": 0.2}) == []
    assert argument_errors(SCHEMA, {"speed": 0.3, "sped": 1, "q": [1, 4]}) == [
        "missing argument 'distance' (number: how far [m])",
        "unknown argument 'sped'; did you mean 'speed'? (expected: distance, speed, q)",
        "argument 'q'[1]: 4 is greater than the maximum of 3",
        "argument 'speed': 0.3 is greater than the maximum of 0.26",
    ]
    assert argument_errors(SCHEMA, {"distance": "far"}) == ["argument 'distance': 'far' is not of type 'number'"]


def _sig(fn) -> inspect.Signature:
    return inspect.signature(fn)


def test_call_arguments_pass_a_variadic_and_what_precedes_it_by_position():
    def move(speed, *q, wait=False): ...
    def walk(distance, speed=0.1): ...

    assert call_arguments(_sig(move), {"q": [1, 2]}) == ((), {"q": [1, 2]})  # speed missing: the check says so
    assert call_arguments(_sig(move), {"speed": 3, "q": [1, 2], "wait": True}) == ((3, 1, 2), {"wait": True})
    assert call_arguments(_sig(walk), {"distance": 1.0}) == ((), {"distance": 1.0})


def test_a_tool_says_what_it_does_to_the_world():
    tool = {
        "name": "base.walk",
        "description": "Drive straight.",
        "kind": "sync",
        "is_tree": False,
        "moves": True,
        "read_only": False,
        "returns": {"description": "how far it went [m]"},
        "parameters": {"type": "object", "properties": {}, "required": []},
    }
    off = mcp_tool(tool)
    assert off["annotations"] == {
        "title": "base.walk",
        "readOnlyHint": False,
        "openWorldHint": True,
        "destructiveHint": True,
    }
    assert off["description"].startswith("Drive straight.\n\nReturns: how far it went [m]\n\nMoves the robot: refused")
    assert "--allow-motion" in off["description"]
    assert mcp_tool(tool, allow_motion=True)["description"].endswith("Moves the robot.")
    assert input_schema(tool)["additionalProperties"] is False
    assert "additionalProperties" not in input_schema(tool, _sig(lambda **kw: None))


def test_settings_default_to_no_motion_and_the_flag_wins():
    assert McpSettings.of(None) == McpSettings(allow_motion=False)
    assert McpSettings.of({"allow_motion": True}).allow_motion is True
    assert McpSettings.of({"allow_motion": True}, allow_motion=False).allow_motion is False
    with pytest.raises(ConfigError, match="unknown settings"):
        McpSettings.of({"allow_moton": True})
    with pytest.raises(ConfigError, match="true or false"):
        McpSettings.of({"allow_motion": "yes"})


@pytest.fixture
def service(monkeypatch):
    monkeypatch.syspath_prepend(str(FIXTURE))
    from fake_robot import FakeRobot

    rt = Runtime()
    rt.add_subsystem("robot", FakeRobot)
    from actors.tutorial import Tutorial

    rt.add_subsystem("tutorial", Tutorial)
    register_tree_folder(rt, FIXTURE / "trees")
    svc = ToolService(rt, McpSettings(allow_motion=True))
    yield svc
    svc.close()
    rt.close()


def _call(service: ToolService, name: str, arguments: dict) -> tuple[dict, list[str]]:
    seen: list[str] = []

    async def report(event: dict) -> None:
        seen.append(f"{event['tree']}:{event['path']} {event['status']}")

    return anyio.run(service.call, name, arguments, report), seen


def test_the_service_runs_a_moving_tree_under_the_virtual_clock(service):
    result, seen = _call(service, "square", {"side": 0.5})
    assert result["structuredContent"]["outputs"] == {"back": -0.1}
    assert result["structuredContent"]["sim_time"] == pytest.approx(0.5 / 0.1 + 0.2 + 0.1 / 0.1, abs=0.05)
    assert seen[0] == "square:sequence running" and "hello:sequence/tutorial.greet success" in seen
    assert _call(service, "robot.odometer", {})[0]["structuredContent"] == {"result": pytest.approx(0.6)}


def test_the_service_checks_before_it_runs(service):
    result, seen = _call(service, "square", {"side": 5.0, "colour": "red"})
    assert result["isError"] and result["structuredContent"]["problems"] == [
        "unknown argument 'colour' (expected: side)"
    ]
    assert seen == []
    assert _call(service, "robot.odometer", {})[0]["structuredContent"] == {"result": 0.0}
    unknown, _ = _call(service, "hullo", {})
    assert unknown["isError"] and "did you mean 'hello'" in unknown["content"][0]["text"]
