"""`actorbt serve` in ROS idiom, seen by a plain rclpy client in another process
(tests/programs/plain_rclpy_client.py: rclpy and actorbt_interfaces only): error codes
of an invalid goal, /actorbt/describe, namespaces (two serves on one domain), the
watched trees folder, feedback with elapsed time and the active node."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

pytest.importorskip("rclpy")
from actorbt_interfaces.action import RunTree  # noqa: E402
from actorbt_interfaces.srv import CallActorNow, Describe  # noqa: E402

from tests.test_ros_common import (
    ROOT,
    STEPS_TREE,
    SUBPROCESS_ENV,
    ServeProcess,
    wait_until,  # noqa: E402
    write_config,
)

ENV = SUBPROCESS_ENV
CLIENT = ROOT / "tests" / "programs" / "plain_rclpy_client.py"
STATUS_ABORTED, STATUS_SUCCEEDED = 6, 4


def serve_in(tmp, *ns_args: str) -> ServeProcess:
    """A serve that records no traces, in a namespace given by ``ns_args``."""
    return ServeProcess(tmp, "--no-record", *ns_args)


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    """Two serves on one domain: robot1 by --namespace, robot2 by --ros-args remapping."""
    one = serve_in(tmp_path_factory.mktemp("robot1"), "--namespace", "robot1")
    two = serve_in(tmp_path_factory.mktemp("robot2"), "--ros-args", "-r", "__ns:=/robot2")
    try:
        assert one.ready.wait(60), one.output()
        assert two.ready.wait(60), two.output()
        yield one, two
    finally:
        one.stop()
        two.stop()


def client(*steps: dict, timeout: float = 90) -> list[dict]:
    proc = subprocess.run(
        [sys.executable, str(CLIENT), json.dumps(list(steps))],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_the_serves_tell_their_names(robots):
    one, two = robots
    assert "  /robot1/actorbt/call" in one.lines and "  /robot1/actorbt/tree/steps_tree" in one.lines
    assert "  /robot1/actorbt/describe" in one.lines
    assert "  /robot2/actorbt/tree/steps_tree" in two.lines


def test_goals_errors_and_feedback_through_a_plain_client(robots):
    one, two = robots
    invalid, unknown_input, good, described, narrowed, unknown, now, now_bad = client(
        {"op": "goal", "action": "/robot1/actorbt/tree/steps_tree", "inputs": "{steps: x}"},
        {"op": "goal", "action": "/robot1/actorbt/tree/steps_tree", "inputs": "{stride: 2}"},
        {"op": "goal", "action": "/robot1/actorbt/tree/steps_tree", "inputs": "{steps: 4, period: 0.05}"},
        {"op": "describe", "service": "/robot1/actorbt/describe"},
        {"op": "describe", "service": "/robot1/actorbt/describe", "name": "work"},
        {"op": "describe", "service": "/robot1/actorbt/describe", "name": "work.ech"},
        {"op": "call_now", "service": "/robot1/actorbt/call_now", "actor": "work.echo", "args": "[1, two]"},
        {"op": "call_now", "service": "/robot1/actorbt/call_now", "actor": "work.nothing"},
    )
    # an invalid goal: accepted, then aborted at once with the code and the reason
    assert invalid["accepted"] and invalid["status"] == STATUS_ABORTED, invalid
    assert invalid["error_code"] == RunTree.Result.INVALID_GOAL == 1001
    assert "expected int" in invalid["error_msg"] and not invalid["success"]
    assert unknown_input["error_code"] == RunTree.Result.INVALID_GOAL
    assert "stride" in unknown_input["error_msg"]

    # a good goal: feedback with the active node and elapsed from the first message on,
    # the last feedback before the result
    assert good["status"] == STATUS_SUCCEEDED and good["error_code"] == RunTree.Result.NONE
    assert good["error_msg"] == "" and "count: 4" in good["outputs_yaml"]
    events = good["events"]
    feedback = [e for e in events if e["type"] == "feedback"]
    assert len(feedback) >= 2, events
    assert feedback[0]["active_node"] and feedback[0]["status"] == "running"
    assert all(fb["active_node"] for fb in feedback), feedback
    elapsed = [fb["elapsed"] for fb in feedback]
    assert elapsed == sorted(elapsed) and 0.0 <= elapsed[0] < 1.0 and elapsed[-1] >= 0.15
    assert any("counting" in fb["active_node"] for fb in feedback), feedback
    assert events[-1]["type"] == "result", events
    assert feedback[-1]["status"] == "success", feedback

    # describe: every served tree and actor as JSON Schema, with the action that runs it
    assert described["error_code"] == Describe.Response.NONE
    doc = described["doc"]
    assert doc["namespace"] == "/robot1" and doc["call_action"] == "/robot1/actorbt/call"
    tools = {t["name"]: t for t in doc["tools"]}
    tree = tools["steps_tree"]
    assert tree["action"] == "/robot1/actorbt/tree/steps_tree" and tree["is_tree"]
    assert tree["action_type"] == "actorbt_interfaces/action/RunTree"
    assert tree["parameters"]["properties"]["steps"]["type"] == "integer"
    assert tree["parameters"]["properties"]["steps"]["default"] == 3
    assert tools["work.slow"]["action"] == "/robot1/actorbt/call"
    assert {t["name"] for t in narrowed["doc"]["tools"]} == {
        "work.slow",
        "work.stats",
        "work.echo",
        "work.boom",
        "work.opaque",
    }
    assert unknown["error_code"] == Describe.Response.UNKNOWN_NAME
    assert "did you mean: work.echo" in unknown["error_msg"]

    # a quick actor as a service
    assert now["success"] and now["error_code"] == 0 and "two" in now["result_yaml"]
    assert now_bad["error_code"] == CallActorNow.Response.INVALID_GOAL
    assert "unknown actor" in now_bad["error_msg"]

    # every goal went to robot1; robot2 heard none of them
    assert wait_until(lambda: any("steps_tree: succeeded" in line for line in one.lines), 5.0)
    assert not any(line.startswith(("goal ", "call ")) for line in two.lines), two.output()


def test_a_goal_reaches_the_robot_it_names(robots):
    one, two = robots
    before = len(one.lines)
    (res,) = client({"op": "goal", "action": "/robot2/actorbt/tree/steps_tree", "inputs": "{steps: 1, period: 0.0}"})
    assert res["status"] == STATUS_SUCCEEDED, res
    assert wait_until(lambda: any("steps_tree: succeeded" in line for line in two.lines), 5.0)
    assert not any(line.startswith("goal ") for line in one.lines[before:])


def test_the_trees_folder_is_watched(robots):
    one, two = robots
    folder = one.tmp / "trees"
    (folder / "late_tree.yaml").write_text(STEPS_TREE.replace("name: steps_tree", "name: late_tree"))
    (folder / "broken_tree.yaml").write_text("name: broken_tree\nroot:\n  sequence:\n    - do: no_such_actor\n")
    added, ran = client(
        {"op": "wait_action", "action": "/robot1/actorbt/tree/late_tree", "present": True},
        {"op": "goal", "action": "/robot1/actorbt/tree/late_tree", "inputs": "{steps: 1, period: 0.0}"},
    )
    assert added["found"], added
    assert ran["status"] == STATUS_SUCCEEDED, ran
    assert wait_until(lambda: "tree late_tree: served on /robot1/actorbt/tree/late_tree" in one.lines, 5.0)
    # the file that does not load is told with its position, and not served
    assert wait_until(
        lambda: any(line.startswith("tree file not served: ") and "broken_tree.yaml:4:" in line for line in one.lines),
        5.0,
    ), one.output()
    assert not any("tree broken_tree: served" in line for line in one.lines)

    (folder / "late_tree.yaml").unlink()
    (gone,) = client({"op": "wait_action", "action": "/robot1/actorbt/tree/late_tree", "present": False})
    assert gone["found"], gone
    assert wait_until(lambda: "tree late_tree: withdrawn /robot1/actorbt/tree/late_tree" in one.lines, 5.0)
    (still,) = client({"op": "goal", "action": "/robot1/actorbt/tree/steps_tree", "inputs": "{steps: 1, period: 0.0}"})
    assert still["status"] == STATUS_SUCCEEDED  # the other trees are served on


def test_the_documented_client_runs(robots, tmp_path):
    """The plain rclpy client in docs/ros-clients.md, as a reader would copy it."""
    text = (ROOT / "docs" / "ros-clients.md").read_text()
    script = text.split("```python\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "plain_client.py"
    path.write_text(script)
    run = [sys.executable, str(path), "/robot1", "steps_tree"]
    ok = subprocess.run(
        [*run, "{steps: 2, period: 0.01}"], cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=60
    )
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "steps_tree: Count steps slowly" in ok.stdout and '"steps": {"type": "integer"' in ok.stdout
    assert "succeeded; outputs: {count: 2}" in ok.stdout
    bad = subprocess.run([*run, "{steps: many}"], cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1, bad.stdout + bad.stderr
    assert f"error_code {RunTree.Result.INVALID_GOAL}: tree 'steps_tree': input 'steps'" in bad.stdout, bad.stdout


def test_the_goal_command_takes_a_namespace(robots):
    one, two = robots
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "bt_cli.main",
            "--config",
            str(two.cfg),
            "goal",
            "steps_tree",
            "--namespace",
            "robot2",
            "--args",
            "{steps: 2, period: 0.01}",
        ],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "status: succeeded" in proc.stdout and "count: 2" in proc.stdout
    assert " s] running" in proc.stdout  # feedback lines show the elapsed time


def test_bad_ros_args_are_told(tmp_path):
    cfg = write_config(tmp_path)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "bt_cli.main",
            "--config",
            str(cfg),
            "serve",
            "--no-record",
            "--ros-args",
            "-r",
            "nonsense",
        ],
        cwd=ROOT,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "actorbt serve: error: invalid ROS arguments '-r nonsense'" in proc.stderr
    assert "Couldn't parse remap rule" in proc.stderr
