"""``serve(rt)`` in one process, real rclpy: tree goals with feedback and results,
CallActor, malformed goals, cancel, a second goal (rejected, or preempting)."""

from __future__ import annotations

import inspect
import json
import threading
import time

import pytest
import yaml

pytest.importorskip("rclpy")
from actorbt_interfaces.action import CallActor, RunTree  # noqa: E402

from bt_engine import Runtime  # noqa: E402
from bt_ros.client import GoalRejectedError  # noqa: E402
from bt_ros.goals import GoalError, parse_call_args, parse_inputs  # noqa: E402
from bt_ros.names import tree_action_name  # noqa: E402
from bt_ros.remote import Remote, RemoteCallError  # noqa: E402
from bt_ros.server import Server, serve  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402
from bt_ros.yamlio import dump  # noqa: E402
from tests.test_ros_common import Work, wait_until, write_trees  # noqa: E402


def _quick_tree(x: int = 1, label: str = "q") -> dict:
    """A tree-like actor (is_tree=True) that is not a YAML mission."""
    return {"double": 2 * x, "label": label}


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("served")
    rt = Runtime(clock="wall", bus=RosTransport)
    remote = server = None
    try:
        rt.add_subsystem("work", Work)
        rt.run_on_hub(
            rt.root.add_actor, "quick_tree", _quick_tree, is_tree=True, signature=inspect.signature(_quick_tree)
        )
        from bt_engine.trees import register_tree_folder

        register_tree_folder(rt, write_trees(tmp / "trees"))
        server = serve(rt, record_dir=tmp / "goals")
        remote = Remote()
        assert remote.wait_for(CallActor, "/actorbt/call", 10.0)
        yield rt, server, remote, tmp
    finally:
        if remote is not None:
            remote.close()
        if server is not None:
            server.close()
        rt.close()


def _feedback_log():
    log: list = []
    lock = threading.Lock()

    def on_feedback(fb):
        with lock:
            log.append((fb.status, fb.active_node, fb.tick_count))

    return log, on_feedback


def test_served_actions(served):
    rt, server, remote, tmp = served
    assert server.actions == ["/actorbt/call", "/actorbt/tree/quick_tree", "/actorbt/tree/steps_tree"]
    assert tree_action_name("nav.patrol") == "/actorbt/tree/nav/patrol"


def test_tree_actor_goal_completes_with_feedback_and_result(served):
    rt, server, remote, tmp = served
    log, on_fb = _feedback_log()
    g = remote.tree_goal("quick_tree", {"x": 21, "label": "z"}, on_feedback=on_fb)
    assert g.wait(10.0)
    assert g.status == "succeeded", g.error
    assert g.result.success and g.result.status == "succeeded"
    assert yaml.safe_load(g.result.outputs_yaml) == {"double": 42, "label": "z"}
    # Not a trees-layer mission: feedback at the start and at the end only.
    assert wait_until(lambda: len(log) >= 2, 2.0), log
    assert log[0][0] == "running" and log[-1][0] == "success"


def test_mission_goal_reports_ticks_and_is_recorded(served):
    rt, server, remote, tmp = served
    log, on_fb = _feedback_log()
    t0 = time.monotonic()
    g = remote.tree_goal("steps_tree", "{steps: 3, period: 0.02}", on_feedback=on_fb)
    assert g.wait(10.0) and g.status == "succeeded", g.error
    assert time.monotonic() - t0 >= 0.06  # the work ran before the goal succeeded
    assert yaml.safe_load(g.result.outputs_yaml) == {"count": 3}
    assert wait_until(lambda: log and log[-1][0] == "success", 2.0)
    ticks = [t for _, _, t in log]
    assert ticks == sorted(ticks) and ticks[-1] >= 2
    assert any("counting" in active for _, active, _ in log), log
    traces = sorted((tmp / "goals").glob("*steps_tree*.jsonl"))
    assert traces, "every tree goal is recorded"
    events = [json.loads(line) for line in traces[-1].read_text().splitlines()]
    assert events[0]["type"] == "header" and events[-1]["type"] in ("end", "txn", "log")
    assert any(e["type"] == "end" and e["status"] == "SUCCESS" for e in events)


def test_a_goal_trace_replays(served, capsys):
    """`actorbt replay` of the trace serve wrote for a goal (wall clock, the recorder opened
    before the run starts), while another caller runs the same tree in the same runtime."""
    from bt_cli.main import main

    rt, server, remote, tmp = served
    before = set((tmp / "goals").glob("*steps_tree*.jsonl"))
    other = threading.Event()
    rt.run_on_hub(lambda: rt.start("steps_tree", steps=4, period=0.015, on_done=lambda _: other.set()))
    g = remote.tree_goal("steps_tree", "{steps: 3, period: 0.02}")
    assert g.wait(10.0) and g.status == "succeeded", g.error
    assert other.wait(10.0)
    new = set((tmp / "goals").glob("*steps_tree*.jsonl")) - before
    assert len(new) == 1, new
    trace = new.pop()
    assert wait_until(lambda: '"phase":"end","txn"' in trace.read_text().splitlines()[-1], 2.0)
    header = json.loads(trace.read_text().splitlines()[0])
    assert header["clock"] == "wall" and header["inputs"] == {"steps": 3, "period": 0.02}
    assert main(["replay", str(trace)]) == 0
    out = capsys.readouterr().out
    assert "replay of steps_tree: OK" in out, out


def test_call_actor_results_and_failures(served):
    rt, server, remote, tmp = served
    assert remote.call("work.echo", 1, "two", k=[3]) == {"args": [1, "two"], "kwargs": {"k": [3]}}
    # a plain list, a mapping of keywords, a scalar
    g = remote.send(CallActor, "/actorbt/call", CallActor.Goal(actor="echo", args_yaml="[1, 2]"))
    assert g.wait(5) and yaml.safe_load(g.result.result_yaml) == {"args": [1, 2], "kwargs": {}}
    g = remote.send(CallActor, "/actorbt/call", CallActor.Goal(actor="echo", args_yaml="{a: 1}"))
    assert g.wait(5) and yaml.safe_load(g.result.result_yaml) == {"args": [], "kwargs": {"a": 1}}
    # values YAML cannot hold come back as their repr
    assert remote.call("work.opaque").startswith("<object object")
    with pytest.raises(RemoteCallError) as e:
        remote.call("work.boom")
    assert e.value.status == "aborted" and "kaput" in str(e.value)
    g = remote.call_goal("work.boom")
    assert g.wait(5) and g.result.error_code == CallActor.Result.ACTOR_FAILED
    assert "ValueError: kaput" in g.result.error_msg
    g = remote.call_goal("work.echo", 1)
    assert g.wait(5) and g.result.error_code == CallActor.Result.NONE and g.result.error_msg == ""


@pytest.mark.parametrize(
    "actor, args_yaml, reason",
    [
        ("work.echo", "[1, 2", "not valid YAML at line 1, column 6: YAML syntax error: the end of the text where"),
        ("no_such_actor", "", "unknown actor"),
        ("work.slow", "{steps: 1, speed: 2}", "bad arguments"),
        ("work.slow", "{args: 3}", "'args' must be a list"),
    ],
)
def test_malformed_calls_are_rejected_with_a_reason(served, actor, args_yaml, reason):
    rt, server, remote, tmp = served
    g = remote.send(CallActor, "/actorbt/call", CallActor.Goal(actor=actor, args_yaml=args_yaml))
    assert g.wait(5.0)
    assert g.status == "rejected"  # accepted, and aborted at once with the reason
    assert isinstance(g.error, GoalRejectedError) and reason in g.error.reason
    assert g.result.error_code == CallActor.Result.INVALID_GOAL and reason in g.result.error_msg
    assert remote.call("work.echo", 5) == {"args": [5], "kwargs": {}}  # still serving


@pytest.mark.parametrize(
    "inputs, reason",
    [
        ("{steps: [", "the text ends inside a value"),
        ("[1, 2]", "must be a mapping"),
        ("{steps: many}", "expected int"),
        ("{stride: 2}", "stride"),
    ],
)
def test_malformed_tree_goals_are_rejected_with_a_reason(served, inputs, reason):
    rt, server, remote, tmp = served
    g = remote.tree_goal("steps_tree", inputs)
    assert g.wait(5.0) and g.status == "rejected"
    assert reason in g.error.reason, g.error.reason
    assert remote.run_tree("steps_tree", {"steps": 1}) == {"count": 1}


def test_cancel_halts_the_tree_and_cancels_its_transactions(served):
    rt, server, remote, tmp = served
    before = remote.call("work.stats")
    log, on_fb = _feedback_log()
    g = remote.tree_goal("steps_tree", {"steps": 500, "period": 0.01}, on_feedback=on_fb)
    assert wait_until(lambda: any("counting" in a for _, a, _ in log), 5.0), log
    g.cancel()
    assert g.wait(5.0)
    assert g.status == "canceled" and not g.result.success and g.result.status == "canceled"
    assert g.result.error_code == RunTree.Result.CANCELED and g.result.error_msg == "goal canceled"
    stats = remote.call("work.stats")
    assert stats["cancelled"] == before["cancelled"] + 1
    assert stats["live"] == []  # nothing the tree started is still running
    assert wait_until(lambda: log[-1][0] == "halted", 2.0), log


def test_a_second_goal_for_a_running_tree_is_rejected_by_default(served):
    rt, server, remote, tmp = served
    first = remote.tree_goal("steps_tree", {"steps": 500, "period": 0.01})
    assert first.accepted.wait(5.0) and first.status == "accepted"
    second = remote.tree_goal("steps_tree", {"steps": 1})
    assert second.wait(5.0) and second.status == "rejected"  # accepted, aborted at once
    assert "already running" in second.error.reason and second.error.code == "BUSY"
    assert second.result.error_code == RunTree.Result.BUSY
    other = remote.tree_goal("quick_tree", {"x": 1})  # other trees are not blocked
    assert other.wait(5.0) and other.status == "succeeded"
    first.cancel()
    assert first.wait(5.0) and first.status == "canceled"


def test_preempt_cancels_the_running_goal_first(served):
    rt, server, remote, tmp = served
    server.preempt = True
    try:
        first = remote.tree_goal("steps_tree", {"steps": 500, "period": 0.01})
        assert first.accepted.wait(5.0)
        second = remote.tree_goal("steps_tree", {"steps": 2})
        assert second.wait(5.0) and first.wait(5.0)
        assert first.status == "aborted" and "preempted" in first.result.status
        assert first.result.error_code == RunTree.Result.PREEMPTED
        assert second.status == "succeeded"
        assert yaml.safe_load(second.result.outputs_yaml) == {"count": 2}
    finally:
        server.preempt = False


def test_goal_yaml_parsing():
    assert parse_inputs("") == {} and parse_inputs("{a: 1}") == {"a": 1}
    assert parse_call_args("") == ([], {})
    assert parse_call_args("[1, x]") == ([1, "x"], {})
    assert parse_call_args("{args: [1], kwargs: {k: 2}}") == ([1], {"k": 2})
    assert parse_call_args("{k: 2}") == ([], {"k": 2})
    assert parse_call_args("7") == ([7], {})
    for bad in ("{1: 2}", "{args: [1], kwargs: [2]}", "!!python/object:os.system ls"):
        with pytest.raises(GoalError):
            parse_call_args(bad)
    assert yaml.safe_load(dump({"t": (1, 2), "s": {3}, "o": RunTree.Goal(inputs_yaml="x")})) == {
        "t": [1, 2],
        "s": [3],
        "o": {"inputs_yaml": "x"},
    }


def test_a_watched_folder_serves_new_trees_and_withdraws_removed_ones(tmp_path):
    """In one process: a tree file added gets its action, removing it ends its running
    goal with TREE_REMOVED and withdraws the action; a broken file is told, not served."""
    from bt_engine.trees import register_tree_folder
    from tests.test_ros_common import STEPS_TREE

    rt = Runtime(clock="wall", bus=RosTransport)
    server = remote = None
    lines: list[str] = []
    try:
        rt.add_subsystem("work", Work)
        folder = write_trees(tmp_path / "trees")
        register_tree_folder(rt, folder)
        server = Server(rt, trees_folder=folder, watch_period=0.05, on_event=lines.append)
        remote = Remote()
        (folder / "more.yaml").write_text(STEPS_TREE.replace("name: steps_tree", "name: more"))
        (folder / "bad.yaml").write_text("name: bad\nroot: {do: work.nothing}\n")
        assert wait_until(lambda: "/actorbt/tree/more" in server.actions, 5.0), lines
        assert "tree more: served on /actorbt/tree/more" in lines
        assert any(line.startswith("tree file not served: ") and "bad.yaml:2:" in line for line in lines), lines
        assert "/actorbt/tree/bad" not in server.actions
        g = remote.tree_goal("more", {"steps": 1000, "period": 0.01})
        assert g.accepted.wait(10.0)
        (folder / "more.yaml").unlink()
        assert g.wait(10.0) and g.status == "aborted", g.status
        assert g.result.error_code == RunTree.Result.TREE_REMOVED
        assert wait_until(lambda: "/actorbt/tree/more" not in server.actions, 5.0)
        assert "tree more: withdrawn /actorbt/tree/more" in lines
        assert rt.run_on_hub(lambda: "more" not in rt.root.actors())
        assert remote.run_tree("steps_tree", {"steps": 1}) == {"count": 1}
    finally:
        if remote is not None:
            remote.close()
        if server is not None:
            server.close()
        rt.close()
