"""Two processes over real DDS (loopback): ``actorbt serve`` on the ROS bus in a
subprocess, and clients here (action-client actors, the Remote client) and in further
subprocesses (``actorbt goal``, ``actorbt rcall``, ``actorbt rshell``). The server is
started once for the module."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time

import pytest
import yaml

pytest.importorskip("rclpy")
from actorbt_interfaces.action import CallActor, RunTree  # noqa: E402

from bt_engine import ActorError, Runtime  # noqa: E402
from bt_ros.remote import Remote  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402
from tests.test_ros_common import (
    ROOT,
    SUBPROCESS_ENV,
    ServeProcess,
    actorbt,
    shm_leaks,  # noqa: E402
    shm_mapped,
    wait_until,
)

ENV = SUBPROCESS_ENV


class Server(ServeProcess):
    """The module's serve: on the ROS bus (``transport: ros`` in the configuration),
    recording its goals."""

    def __init__(self, tmp):
        super().__init__(tmp, "--record-dir", str(tmp / "goals"))
        self.segments: set[str] = set()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = Server(tmp_path_factory.mktemp("serve"))
    try:
        assert s.ready.wait(30), s.output()
        yield s
    finally:
        s.stop()


@pytest.fixture(scope="module")
def client(server):
    rt = Runtime(clock="wall", bus=RosTransport)
    remote = None
    try:
        rt.run_on_hub(rt.bus.register_action, rt.root, "remote_call", CallActor, "/actorbt/call")
        rt.run_on_hub(rt.bus.register_action, rt.root, "steps", RunTree, "/actorbt/tree/steps_tree")
        remote = Remote()
        yield rt, remote
    finally:
        if remote is not None:
            remote.close()
        rt.close()


def test_action_client_actors_reach_a_server_in_another_process(server, client):
    rt, remote = client
    # the first goal waits for discovery (about 2 s between processes)
    res = rt.call("remote_call", actor="work.echo", args_yaml="[1, two]")
    assert res.success and yaml.safe_load(res.result_yaml) == {"args": [1, "two"], "kwargs": {}}
    res = rt.call("steps", inputs_yaml="{steps: 2, period: 0.01}")
    assert res.success and res.status == "succeeded"
    assert yaml.safe_load(res.outputs_yaml) == {"count": 2}
    with pytest.raises(ActorError) as e:  # accepted, aborted at once with the reason
        rt.call("steps", inputs_yaml="{steps: lots}")
    assert "ended aborted" in str(e.value) and "expected int" in str(e.value)
    assert f"(error_code {RunTree.Result.INVALID_GOAL})" in str(e.value)


def test_goal_with_feedback_and_cancel_mid_run(server, client):
    rt, remote = client
    before = remote.call("work.stats")
    feedback: list = []
    g = remote.tree_goal(
        "steps_tree",
        {"steps": 1000, "period": 0.01},
        on_feedback=lambda fb: feedback.append((fb.status, fb.active_node, fb.tick_count)),
    )
    assert wait_until(lambda: any("counting" in a for _, a, _ in feedback), 10.0), feedback
    assert feedback[0][0] == "running"
    t0 = time.monotonic()
    g.cancel()
    assert g.wait(5.0)
    cancel_latency = time.monotonic() - t0
    assert g.status == "canceled" and g.result.status == "canceled" and not g.result.success
    assert cancel_latency < 1.0
    stats = remote.call("work.stats")
    assert stats["cancelled"] == before["cancelled"] + 1 and stats["live"] == []

    # the server's trace of the goal: the leaf's actor call and its transaction cancelled
    def trace_events():
        files = sorted((server.tmp / "goals").glob("*steps_tree*.jsonl"), key=os.path.getmtime)
        return [json.loads(line) for line in files[-1].read_text().splitlines()] if files else []

    assert wait_until(lambda: any(e["type"] == "end" for e in trace_events()), 5.0)
    events = trace_events()
    assert events[0]["type"] == "header" and events[0]["tree"] == "steps_tree"
    assert any(e["type"] == "return" and e["actor"] == "work.slow" and e["state"] == "cancelled" for e in events)
    assert any(
        e["type"] == "txn" and e["phase"] == "end" and e["actor"] == "work.slow" and e["state"] == "cancelled"
        for e in events
    )
    assert [e["status"] for e in events if e["type"] == "end"] == ["INVALID"]


def test_malformed_goal_is_rejected_and_the_server_keeps_serving(server, client):
    rt, remote = client
    g = remote.tree_goal("steps_tree", "{steps: [")
    assert g.wait(5.0) and g.status == "rejected"
    assert "not valid YAML" in g.error.reason
    g = remote.send(CallActor, "/actorbt/call", CallActor.Goal(actor="work.nothing"))
    assert g.wait(5.0) and g.status == "rejected" and "unknown actor" in g.error.reason
    assert remote.run_tree("steps_tree", {"steps": 1, "period": 0.0}) == {"count": 1}


def test_goal_and_rcall_commands(server):
    cfg = str(server.cfg)
    goal = actorbt("--config", cfg, "goal", "steps_tree", "--args", "{steps: 3, period: 0.01}")
    rcall = actorbt("--config", cfg, "rcall", "work.echo", "1", "k='v'")
    bad = actorbt("--config", cfg, "goal", "steps_tree", "--args", "{steps: x}")
    out, _ = goal.communicate(timeout=30)
    assert goal.returncode == 0, out
    assert "status: succeeded" in out and "[tick" in out and "count: 3" in out
    out, _ = rcall.communicate(timeout=30)
    assert rcall.returncode == 0, out
    assert "{'args': [1], 'kwargs': {'k': 'v'}}" in out
    out, _ = bad.communicate(timeout=30)
    assert bad.returncode == 2 and "refused the goal (INVALID_GOAL)" in out and "expected int" in out


def test_serve_tells_how_its_start_up_goes(server):
    out = server.output()
    assert "actorbt serve: loading subsystems work and the trees in" in out
    assert re.search(r"actorbt serve: actors and trees loaded at \d+\.\d s", out), out
    assert re.search(r"actorbt serve: ready in \d+\.\d s", out), out


def test_goal_for_a_tree_that_is_not_served_fails_at_once(server):
    t0 = time.monotonic()
    proc = actorbt("--config", str(server.cfg), "goal", "steps_tre", "--args", "{steps: 1}")
    out, _ = proc.communicate(timeout=30)
    took = time.monotonic() - t0
    assert proc.returncode == 2, out
    assert "no served tree 'steps_tre'; did you mean: steps_tree?" in out
    assert "(served: steps_tree)" in out
    assert took < 8.0, f"{took:.1f} s: it waited for the server instead of failing"  # --wait is 10 s


def test_rcall_of_an_unknown_actor_lists_close_matches(server):
    proc = actorbt("--config", str(server.cfg), "rcall", "work.ech", "1")
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 2, out
    assert "refused the call (INVALID_GOAL): unknown actor 'work.ech'; did you mean: work.echo" in out


def test_rshell_runs_calls_from_piped_lines(server):
    lines = "\n".join(
        ["work.echo 1 k='v'", "work.boom", "help work.echo", "no_such_actor", "trees", "work.echo [2,3]", ""]
    )
    proc = subprocess.run(
        [sys.executable, "-m", "bt_cli.main", "--config", str(server.cfg), "rshell"],
        cwd=ROOT,
        env=ENV,
        input=lines,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = proc.stdout
    assert "{'args': [1], 'kwargs': {'k': 'v'}}" in out
    assert "error: actor work.boom aborted" in out or "error: actor work.boom failed" in out, out
    assert "kaput" in out
    assert "work.echo(*args, **kwargs) -> dict  [sync]" in out  # help, from the actor index
    assert "error: refused (INVALID_GOAL): unknown actor 'no_such_actor'" in out
    assert "  steps_tree" in out  # trees
    assert "{'args': [[2, 3]], 'kwargs': {}}" in out
    assert "connected in" in proc.stderr


def test_serve_prints_one_line_per_goal(server):
    # the goals of the tests above, as the server told them; a goal's line comes once the
    # server has finished with it, which on a loaded machine can be after its client returned
    def has(pattern: str) -> bool:
        return wait_until(lambda: any(re.fullmatch(pattern, line) for line in server.lines), 5.0)

    gid = r"[0-9a-f]{8}"
    assert has(rf"goal {gid} steps_tree: succeeded in \d+\.\d+ s \(trace .*steps_tree.*\.jsonl\)"), server.output()
    assert has(rf"goal {gid} steps_tree \{{steps: 3, period: 0\.01\}}: accepted")
    assert has(rf"goal {gid} steps_tree: canceled in \d+\.\d+ s \(trace .*\.jsonl\)")
    assert has(rf"goal {gid} steps_tree \{{steps: x\}}: refused \(INVALID_GOAL\): .*expected int.*")
    assert has(rf"call {gid} work\.echo\(1, k='v'\): succeeded in \d+\.\d+ s")
    assert has(rf"call {gid} work\.boom\(\): failed: .*kaput in \d+\.\d+ s")
    assert has(
        rf"call {gid} work\.ech\(1\): refused \(INVALID_GOAL\): unknown actor 'work\.ech'; "
        r"did you mean: work\.echo.*"
    )
    # one line each: no goal is told twice
    end = re.compile(rf"(goal|call) {gid} .*: (succeeded|failed|canceled|aborted)")
    ends = [line for line in server.lines if end.match(line)]
    ids = [line.split()[1] for line in ends]
    assert len(ids) == len(set(ids)), ends


def test_server_shuts_down_cleanly(server):
    segments = shm_mapped(server.proc.pid)
    assert segments, "the server maps Fast DDS shared memory while it runs"
    assert server.stop() == 0, server.output()
    assert "actorbt serve: stopped" in server.output()
    assert shm_leaks(segments) == set()
