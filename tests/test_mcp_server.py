"""``actorbt mcp`` as a client sees it: the server runs as a subprocess on a small
project without a simulator (tests/fixtures/mcp: the tutorial, a fake robot that
declares motion and limits, three trees), driven with the MCP SDK's stdio client."""

from __future__ import annotations

import json
import pathlib
import shutil
import subprocess
import sys
import threading
from typing import Any, Awaitable, Callable

import anyio
import pytest
from mcp.client.session import ClientSession
from mcp.client.stdio import StdioServerParameters, stdio_client

REPO = pathlib.Path(__file__).resolve().parents[1]
FIXTURE = REPO / "tests" / "fixtures" / "mcp"
MISSION_TOOLS = {"validate_mission", "run_mission", "show_tree", "get_trace"}
#: the longest a scenario may take, server start included [s]
SCENARIO_TIMEOUT = 60


@pytest.fixture
def project(tmp_path) -> pathlib.Path:
    """A copy of the fixture project (the server writes its actor index beside it)."""
    dst = tmp_path / "project"
    shutil.copytree(FIXTURE, dst, ignore=shutil.ignore_patterns(".actorbt", "__pycache__"))
    return dst


def _command(project: pathlib.Path, *args: str) -> list[str]:
    return ["-m", "bt_cli.main", "--config", str(project / "actorbt.yaml"), *args]


def _env(project: pathlib.Path) -> dict[str, str]:
    return {"PYTHONPATH": str(project), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


def with_server(project: pathlib.Path, scenario: Callable[[ClientSession], Awaitable[Any]], *options: str) -> Any:
    """Start ``actorbt mcp OPTIONS`` on ``project``, run ``scenario(session)`` against it."""
    params = StdioServerParameters(
        command=sys.executable, args=_command(project, "mcp", *options), cwd=str(project), env=_env(project)
    )

    async def main() -> Any:
        with anyio.fail_after(SCENARIO_TIMEOUT):
            async with stdio_client(params) as (read, write):
                async with ClientSession(read, write) as session:
                    await session.initialize()
                    return await scenario(session)

    return anyio.run(main)


def _text(result: Any) -> str:
    return "\n".join(c.text for c in result.content if c.type == "text")


def test_the_tools_are_the_catalog_and_the_mission_tools(project):
    catalog = json.loads(
        subprocess.run(
            [sys.executable, *_command(project, "catalog", "--json")],
            cwd=project,
            env={**_env(project), "PATH": ""},
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )

    async def scenario(session: ClientSession) -> Any:
        return (await session.list_tools()).tools

    tools = {t.name: t for t in with_server(project, scenario)}
    assert set(tools) == {t["name"] for t in catalog} | MISSION_TOOLS
    for entry in catalog:
        tool = tools[entry["name"]]
        schema = dict(tool.input_schema)
        assert schema.pop("additionalProperties") is False
        assert schema == entry["parameters"]
        assert tool.description.startswith(entry["description"])
        assert tool.annotations.read_only_hint is entry["read_only"]
        assert tool.annotations.open_world_hint is entry["moves"]
        assert tool.meta["actorbt"]["moves"] is entry["moves"]
    assert tools["robot.drive"].annotations.destructive_hint is True
    assert tools["robot.drive"].input_schema["properties"]["speed"]["maximum"] == 0.26
    assert "refused while motion is off" in tools["robot.drive"].description
    assert tools["square"].meta["actorbt"]["moves"] is True  # it calls robot.drive
    assert tools["hello"].annotations.read_only_hint is True  # it calls tutorial.greet only


def test_a_tree_reports_every_node_transition_and_returns_its_outputs(project):
    async def scenario(session: ClientSession) -> Any:
        progress: list[tuple[float, str | None]] = []

        async def on_progress(value: float, total: float | None, message: str | None) -> None:
            progress.append((value, message))

        result = await session.call_tool("hello", {"name": "ada"}, progress_callback=on_progress)
        trace = await session.call_tool("get_trace", {"types": ["status", "end"]})
        return progress, result, trace

    progress, result, trace = with_server(project, scenario)
    assert [m for _, m in progress] == [
        "hello:sequence running",
        "hello:sequence/wait 0.2s running",
        "hello:sequence/wait 0.2s success",
        "hello:sequence/tutorial.greet running",
        "hello:sequence/tutorial.greet success",
        "hello:sequence success",
    ]
    assert [v for v, _ in progress] == list(range(1, len(progress) + 1))
    assert not result.is_error
    assert result.structured_content["status"] == "SUCCESS"
    assert result.structured_content["outputs"] == {"greeting": "hello, ada"}
    assert result.structured_content["ticks"] >= 2
    assert _text(result).startswith("hello: SUCCESS after")
    events = trace.structured_content["events"]
    assert trace.structured_content["tool"] == "hello"
    assert events[-1]["type"] == "end" and events[-1]["outputs"] == {"greeting": "hello, ada"}
    assert {e["type"] for e in events} == {"status", "end"}


def test_bad_arguments_are_refused_by_name_and_nothing_moves(project):
    async def scenario(session: ClientSession) -> Any:
        return [
            await session.call_tool(name, args)
            for name, args in [
                ("tutorial.greet", {"nme": "ada"}),
                ("robot.drive", {"distance": 0.5, "speed": 2.0}),  # over the declared limit
                ("robot.drive", {"speed": 0.1}),  # distance missing
                ("robot.drive", {"distance": "far"}),
                ("robot.move_joint", {"q": [0.1, 9.0]}),
                ("hello", {"name": 3}),
                ("robot.odometer", {}),
            ]
        ]

    typo, too_fast, missing, wrong_type, joint, tree_input, odometer = with_server(project, scenario, "--allow-motion")
    assert typo.is_error and "unknown argument 'nme'; did you mean 'name'?" in _text(typo)
    assert too_fast.is_error and "argument 'speed': 2.0 is greater than the maximum of 0.26" in _text(too_fast)
    assert missing.is_error and "missing argument 'distance'" in _text(missing)
    assert wrong_type.is_error and "argument 'distance'" in _text(wrong_type)
    assert joint.is_error and "argument 'q'[1]" in _text(joint)
    assert tree_input.is_error and "argument 'name'" in _text(tree_input)
    for refused in (typo, too_fast, missing, wrong_type, joint, tree_input):
        assert refused.structured_content["refused"] == "arguments"
    assert odometer.structured_content == {"result": 0.0}  # the base never moved


def test_motion_is_refused_unless_allowed(project):
    drive_mission = "name: out_and_back\nroot:\n  sequence:\n    - do: drive\n      with: {distance: 0.2}\n"

    async def scenario(session: ClientSession) -> Any:
        return [
            await session.call_tool("robot.drive", {"distance": 0.2}),
            await session.call_tool("square", {}),
            await session.call_tool("run_mission", {"yaml": drive_mission}),
            await session.call_tool("robot.odometer", {}),
        ]

    for refused in with_server(project, scenario)[:3]:
        assert refused.is_error and refused.structured_content == {"refused": "motion"}
        assert "actorbt mcp --allow-motion" in _text(refused)
        assert "mcp: {allow_motion: true}" in _text(refused)
    (project / "actorbt.yaml").write_text((project / "actorbt.yaml").read_text() + "mcp: {allow_motion: true}\n")
    drive, square, mission, odometer = with_server(project, scenario)
    assert drive.structured_content == {"result": 0.2}
    assert square.structured_content["outputs"] == {"back": -0.1}
    assert mission.structured_content["status"] == "SUCCESS"
    assert odometer.structured_content["result"] == pytest.approx(0.2 + 0.3 + 0.2)


def test_cancel_halts_the_tree_and_the_server_keeps_serving(project):
    async def scenario(session: ClientSession) -> Any:
        waiting = anyio.Event()

        async def on_progress(value: float, total: float | None, message: str | None) -> None:
            if message == "wait_long:sequence/wait 600s running":
                waiting.set()

        async with anyio.create_task_group() as tg:

            async def call() -> None:
                await session.call_tool("wait_long", {}, progress_callback=on_progress)
                raise AssertionError("wait_long ended by itself")

            tg.start_soon(call)
            await waiting.wait()
            tg.cancel_scope.cancel()  # the client sends notifications/cancelled
        trace = await session.call_tool("get_trace", {"types": ["status", "end"]})
        return trace, await session.call_tool("tutorial.greet", {"name": "again"})

    trace, after = with_server(project, scenario, "--clock", "wall")
    assert after.structured_content == {"result": "hello, again"}
    content = trace.structured_content
    assert content["tool"] == "wait_long" and content["outcome"]["status"] == "CANCELLED", content["outcome"]
    halted = {
        e["path"]
        for e in content["events"]
        if e["type"] == "status" and e["old"] == "RUNNING" and e["new"] == "INVALID"
    }
    assert halted == {"sequence", "sequence/wait 600s"}
    assert content["events"][-1]["type"] == "end" and content["events"][-1]["status"] == "INVALID"


def test_mission_tools_validate_show_and_run_drafts(project):
    typo = "name: draft\nroot:\n  do: tutorial.gret\n"
    good = (
        "name: draft\ninputs:\n  who: {type: str, default: bob}\noutputs: [g]\n"
        'root:\n  sequence:\n    - do: hello\n      with: {name: "{who}"}\n      out: h\n'
        '    - do: tutorial.greet\n      with: {name: "{who}"}\n      out: g\n'
    )

    async def scenario(session: ClientSession) -> Any:
        progress: list[str | None] = []

        async def on_progress(value: float, total: float | None, message: str | None) -> None:
            progress.append(message)

        return (
            await session.call_tool("validate_mission", {"yaml": typo}),
            await session.call_tool("validate_mission", {"yaml": "name: x\nroot: [\n"}),
            await session.call_tool("validate_mission", {"yaml": good}),
            await session.call_tool("show_tree", {"tree": "hello"}),
            await session.call_tool("show_tree", {"tree": "helo"}),
            await session.call_tool(
                "run_mission", {"yaml": good, "inputs": {"who": "cy"}}, progress_callback=on_progress
            ),
            await session.call_tool("run_mission", {"yaml": typo}),
            (await session.list_tools()).tools,
            progress,
        )

    bad, broken, valid, shown, unknown, ran, not_run, tools, progress = with_server(project, scenario)
    assert bad.is_error
    [error] = bad.structured_content["errors"]
    assert (error["line"], error["column"]) == (3, 7) and "did you mean 'tutorial.greet'" in error["message"]
    assert _text(bad).startswith("1 error(s):\n3:7: unknown actor 'tutorial.gret'")
    [syntax] = broken.structured_content["errors"]
    assert broken.is_error and syntax["kind"] == "MissionSyntaxError" and syntax["line"] == 3  # at the end
    assert valid.structured_content == {"valid": True, "errors": []}
    assert "tutorial.greet" in _text(shown) and "wait" in _text(shown)
    assert unknown.is_error and "did you mean 'hello'" in _text(unknown)
    assert ran.structured_content["outputs"] == {"g": "hello, cy"}
    assert "draft:sequence/hello running" in progress and "hello:sequence/tutorial.greet success" in progress
    assert not_run.is_error and "not run" in _text(not_run)
    assert "draft" not in {t.name for t in tools}  # a draft is not registered


def test_the_project_catalog_is_served_with_its_motion_marked():
    """The real actorbt.yaml, without a world: the robot's actors as tools, motion refused."""
    params = StdioServerParameters(
        command=sys.executable,
        args=["-m", "bt_cli.main", "mcp", "--world", "none"],
        cwd=str(REPO),
        env={"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
    )

    async def main() -> Any:
        with anyio.fail_after(SCENARIO_TIMEOUT):
            async with stdio_client(params) as (read, write):
                async with ClientSession(read, write) as session:
                    await session.initialize()
                    tools = {t.name: t for t in (await session.list_tools()).tools}
                    return tools, await session.call_tool("bt_pick_place", {})

    tools, refused = anyio.run(main)
    for name in ("robot.navigation.goto", "robot.navigation.cmd_vel", "robot.arm.move_joint", "bt_pick_place"):
        assert tools[name].meta["actorbt"]["moves"] is True, name
    assert tools["robot.navigation.get_pose"].annotations.read_only_hint is True
    assert tools["robot.navigation.mini_walk"].input_schema["properties"]["speed"]["maximum"] == 0.26
    assert refused.is_error and refused.structured_content == {"refused": "motion"}


def test_the_wire_carries_only_protocol_messages(project):
    # robot.chatter writes to fd 1 and to C's stdout, as pybullet does
    hello = {
        "jsonrpc": "2.0",
        "id": 1,
        "method": "initialize",
        "params": {"protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": {"name": "raw", "version": "0"}},
    }
    chatter = {"jsonrpc": "2.0", "id": 2, "method": "tools/call", "params": {"name": "robot.chatter", "arguments": {}}}
    proc = subprocess.Popen(
        [sys.executable, *_command(project, "mcp")],
        cwd=str(project),
        env=_env(project),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    killer = threading.Timer(SCENARIO_TIMEOUT, proc.kill)
    killer.start()
    try:
        for message in (hello, {"jsonrpc": "2.0", "method": "notifications/initialized"}, chatter):
            proc.stdin.write(json.dumps(message) + "\n")
        proc.stdin.flush()
        replies = []
        while len(replies) < 2:
            line = proc.stdout.readline()
            assert line, "the server ended before answering"
            replies.append(json.loads(line))  # every line on the wire is JSON-RPC
        rest, err = proc.communicate()  # closes stdin: the server ends
    finally:
        killer.cancel()
    assert [r.get("id") for r in replies] == [1, 2] and not replies[1]["result"].get("isError")
    assert all(json.loads(line) for line in rest.splitlines())
    assert "raw line on fd 1" in err and "buffered C stdout line" in err
