"""Trees run as actors: event-driven ticks, halting and cancellation, trees calling
trees, every call mode, blackboard isolation and clean-up."""

from __future__ import annotations

import textwrap
import time
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Status

from bt_engine import ActorError, Runtime, SubSystem, actor
from bt_engine.trees import InputError, TreeFailure, TreeHost, TreeObserver, register_tree_folder, tree_host
from bt_engine.trees.testing import ScriptedActors

REPO_TREES = Path(__file__).parent.parent / "trees"


class Recorder(TreeObserver):
    def __init__(self) -> None:
        self.events: list[tuple] = []

    def run_started(self, run) -> None:
        self.events.append(("start", run.mission.name, run.depth))

    def tick(self, run) -> None:
        self.events.append(("tick", run.mission.name, run.ticks, run.rt.now()))

    def status_changed(self, run, path, old, new) -> None:
        self.events.append(("status", run.mission.name, path, old.name, new.name))

    def blackboard_write(self, run, key, value) -> None:
        self.events.append(("write", run.mission.name, key, value))

    def run_finished(self, run, status, outcome) -> None:
        self.events.append(("end", run.mission.name, status.name))

    def ticks(self, tree: str) -> int:
        return sum(1 for e in self.events if e[0] == "tick" and e[1] == tree)


def write_trees(folder: Path, **trees: str) -> Path:
    for name, body in trees.items():
        (folder / f"{name}.yaml").write_text(textwrap.dedent(body))
    return folder


def host_for(rt: Runtime, folder: Path, **options: Any) -> tuple[TreeHost, ScriptedActors, Recorder]:
    script = rt.add_subsystem("script", ScriptedActors)
    host = TreeHost(rt, **options)
    host.load_folder(folder)
    recorder = Recorder()
    host.observers.append(recorder)
    return host, script, recorder


def assert_clean(rt: Runtime, host: TreeHost) -> None:
    deadline = time.monotonic() + 2.0
    while rt.stats() != {"transactions": 0, "tasks": 0} and time.monotonic() < deadline:
        time.sleep(0.001)
    assert rt.stats() == {"transactions": 0, "tasks": 0}
    assert host.live_runs() == []
    assert not [k for k in py_trees.blackboard.Blackboard.storage if k.startswith("/actorbt/")]
    assert not [c for c in py_trees.blackboard.Blackboard.clients.values() if c.startswith("actorbt:")]


def test_demo_patrol_runs_on_virtual_time(rt: Runtime, tmp_path: Path) -> None:
    # the repo's trees folder also holds the robot missions, which need the robot's actors
    (tmp_path / "demo_patrol.yaml").write_text((REPO_TREES / "demo_patrol.yaml").read_text())
    host = register_tree_folder(rt, tmp_path)
    assert tree_host(rt) is host
    assert rt.resolve("demo_patrol").is_tree
    started = time.perf_counter()
    assert rt.call("demo_patrol") == {"last": "bedroom"}
    assert rt.now() == pytest.approx(14.5)
    assert time.perf_counter() - started < 2.0
    assert rt.call("demo_patrol", rounds=1, pause=0.0) == {"last": "bedroom"}
    assert_clean(rt, host)


def test_a_tree_waiting_on_a_long_actor_ticks_only_on_events(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        idle="""
        name: idle
        root: {do: block, with: {tag: long, seconds: 60}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    assert rt.call("idle") == {}
    assert rt.now() == pytest.approx(60.0)
    assert rec.ticks("idle") == 2  # start, and the actor's end


def test_max_period_bounds_the_time_between_ticks(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        idle="""
        name: idle
        root: {do: block, with: {tag: long, seconds: 10}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path, max_period=1.0)
    rt.call("idle")
    assert rec.ticks("idle") == 11


def test_deadlines_wake_the_tick_loop(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        deadlines="""
        name: deadlines
        root:
          sequence:
            - wait: 2
            - selector:
                - timeout: {seconds: 3, child: {do: block, with: {tag: slow, seconds: 100}}}
                - set: {fallback: true}
            - wait: 0.5
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    rt.call("deadlines")
    assert rt.now() == pytest.approx(5.5)
    assert [e[3] for e in rec.events if e[0] == "tick"] == pytest.approx([0.0, 2.0, 5.0, 5.5])
    assert script.cancelled == ["slow"]
    assert_clean(rt, host)


def test_retry_and_repeat_restart_without_waiting(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        restarts="""
        name: restarts
        root:
          sequence:
            - retry: {times: 3, child: {do: flaky, with: {tag: f, failures: 2}}}
            - repeat: {times: 3, child: {do: echo, with: {value: 1}}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    assert rt.call("restarts") == {}
    assert script.started == ["f", "f", "f"]
    assert rt.now() == 0.0


def test_halting_a_subtree_cancels_its_actors(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        race="""
        name: race
        root:
          parallel:
            policy: success_on_one
            children:
              - {do: block, with: {tag: loser, seconds: 100}}
              - {do: act, with: {tag: loser_async}}
              - {do: block, with: {tag: winner, seconds: 1}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    assert rt.call("race") == {}
    assert sorted(script.cancelled) == ["loser", "loser_async"]
    assert rt.now() == pytest.approx(1.0)
    assert_clean(rt, host)


def test_cancelling_the_tree_transaction_reaches_the_actor(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        long="""
        name: long
        root:
          sequence:
            - {do: act, with: {tag: a}}
    """,
        outer="""
        name: outer
        root: {do: long}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    outcomes: list[Any] = []
    txn = rt.start("outer", on_done=outcomes.append)
    deadline = time.monotonic() + 2
    while "a" not in script.started and time.monotonic() < deadline:
        time.sleep(0.001)
    txn.cancel("operator abort")
    while not outcomes and time.monotonic() < deadline:
        time.sleep(0.001)
    assert outcomes and not outcomes[0] and outcomes[0].cancelled
    assert script.cancelled == ["a"]
    ends = [e for e in rec.events if e[0] == "end"]
    assert ends == [("end", "long", "INVALID"), ("end", "outer", "INVALID")]
    assert_clean(rt, host)


def test_a_tree_called_from_python_a_tree_and_an_actor_gives_the_same_result(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        pick="""
        name: pick
        inputs:
          target: str
          tries: {type: int, default: 2}
        outputs: [grasp]
        root:
          sequence:
            - retry: {times: "{tries}", child: {do: flaky, with: {tag: "{target}", failures: 1}}}
            - {do: echo, with: {value: {target: "{target}", ok: true}}, out: grasp}
    """,
        pick_place="""
        name: pick_place
        inputs: {target: str}
        outputs: [result]
        root:
          sequence:
            - {do: pick, with: {target: "{target}"}, out: picked}
            - set: {result: "{picked}"}
    """,
    )

    class Caller(SubSystem):
        @actor
        def via_actor(self, target: str) -> Any:
            return self.run_actor("pick", target)

    host, script, rec = host_for(rt, tmp_path)
    rt.add_subsystem("caller", Caller)
    expected = {"grasp": {"target": "can", "ok": True}}
    assert rt.call("pick", "can") == expected
    assert rt.call("pick_place", target="can") == {"result": expected}
    assert rt.call("via_actor", "can") == expected
    assert script.started == ["can"] * 4  # flaky fails only the first time for a tag
    assert_clean(rt, host)


def test_trees_answer_every_call_mode(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        echo_tree="""
        name: echo_tree
        inputs: {v: any}
        outputs: [v]
        root: {wait: 1}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    assert rt.run_actor("echo_tree", 1) == {"v": 1}
    results: list[Any] = []
    txn = rt.run_actor_mode("echo_tree", "async", results.append, 2)
    deadline = time.monotonic() + 2
    while not txn.done and time.monotonic() < deadline:
        time.sleep(0.001)
    assert results == [{"v": 2}]
    assert rt.run_actor_mode("echo_tree", "timed", 5.0, 3) == {"v": 3}
    with rt.stream("echo_tree", 4) as it:
        assert [next(it), next(it)] == [{"v": 4}, {"v": 4}]
    assert_clean(rt, host)


def test_recursion_five_deep_passes_inputs_and_outputs(rt: Runtime, tmp_path: Path) -> None:
    trees = {}
    for level in range(1, 5):
        trees[f"level{level}"] = f"""
            name: level{level}
            inputs: {{value: any}}
            outputs: [value]
            root:
              sequence:
                - {{do: level{level + 1}, with: {{value: [l{level}, "{{value}}"]}}, out: r}}
                - set: {{value: "{{r.value}}"}}
        """
    trees["level5"] = """
        name: level5
        inputs: {value: any}
        outputs: [value]
        root: {set: {value: [l5, "{value}"]}}
    """
    write_trees(tmp_path, **trees)
    host, script, rec = host_for(rt, tmp_path)
    result = rt.call("level1", "x")
    assert result == {"value": ["l5", ["l4", ["l3", ["l2", ["l1", "x"]]]]]}
    starts = [e for e in rec.events if e[0] == "start"]
    assert [(name, depth) for _, name, depth in starts] == [(f"level{i}", i - 1) for i in range(1, 6)]
    assert_clean(rt, host)


def test_same_tree_twice_in_parallel_keeps_separate_blackboards(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        sub="""
        name: sub
        inputs: {tag: str, seconds: float}
        outputs: [got]
        root: {do: block, with: {tag: "{tag}", seconds: "{seconds}"}, out: got}
    """,
        both="""
        name: both
        outputs: [a, b]
        root:
          parallel:
            - {do: sub, with: {tag: first, seconds: 2}, out: a}
            - {do: sub, with: {tag: second, seconds: 1}, out: b}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    assert rt.call("both") == {"a": {"got": "first"}, "b": {"got": "second"}}
    assert_clean(rt, host)


def test_tree_failure_names_the_failed_node(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        fails="""
        name: fails
        root:
          sequence:
            - set: {n: 1}
            - {name: must hold, check: n > 5}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    with pytest.raises(ActorError) as info:
        rt.call("fails")
    failure = info.value.__cause__
    assert isinstance(failure, TreeFailure)
    assert failure.node_path == "sequence/must hold"
    assert failure.reason == "n > 5: false"
    assert str(failure) == "tree fails failed at sequence/must hold: n > 5: false"
    assert_clean(rt, host)


def test_bad_inputs_fail_at_the_call_site(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        typed="""
        name: typed
        inputs: {n: int}
        root: {wait: "{n}"}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    with pytest.raises(ActorError) as info:
        rt.call("typed", n="three")
    assert isinstance(info.value.__cause__, InputError)
    with pytest.raises(Exception, match="missing a required argument"):
        rt.call("typed")
    assert rt.call("typed", 2) == {}


def test_observers_see_ticks_status_changes_and_writes(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        small="""
        name: small
        inputs: {x: {type: int, default: 1}}
        root:
          sequence:
            - {name: get, do: echo, with: {value: 7}, out: y}
            - {name: check, check: y == 7}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    rt.call("small")
    assert rec.events == [
        ("write", "small", "x", 1),
        ("start", "small", 0),
        ("tick", "small", 1, 0.0),
        ("status", "small", "sequence", "INVALID", "RUNNING"),
        ("status", "small", "sequence/get", "INVALID", "RUNNING"),
        ("tick", "small", 2, 0.0),
        ("write", "small", "y", 7),
        # as it happened: the children end before the sequence does
        ("status", "small", "sequence/get", "RUNNING", "SUCCESS"),
        ("status", "small", "sequence/check", "INVALID", "SUCCESS"),
        ("status", "small", "sequence", "RUNNING", "SUCCESS"),
        ("end", "small", "SUCCESS"),
    ]


def test_behaviour_nodes_use_registered_py_trees_behaviours(rt: Runtime, tmp_path: Path) -> None:
    class CountDown(py_trees.behaviour.Behaviour):
        """Running for ``n`` ticks, then writes ``done`` in the run's namespace."""

        def __init__(self, name: str, n: int, blackboard_namespace: str) -> None:
            super().__init__(name)
            self.n = n
            self.bb = self.attach_blackboard_client(namespace=blackboard_namespace)
            self.bb.register_key("done", access=py_trees.common.Access.WRITE)

        def update(self) -> Status:
            self.n -= 1
            if self.n > 0:
                return Status.RUNNING
            self.bb.done = "yes"
            return Status.SUCCESS

    write_trees(
        tmp_path,
        counting="""
        name: counting
        inputs: {n: {type: int, default: 3}}
        outputs: [done]
        root:
          sequence:
            - behaviour: CountDown
              with: {n: "{n}"}
              writes: [done]
            - check: done == "yes"
    """,
    )
    host, script, rec = host_for(rt, tmp_path, behaviours={"CountDown": CountDown})
    assert rt.call("counting") == {"done": "yes"}
    assert rec.ticks("counting") == 3  # polled every behaviour_period
    assert rt.now() == pytest.approx(0.2)


def test_a_tree_may_not_replace_a_root_actor(rt: Runtime, tmp_path: Path) -> None:
    from bt_engine.trees import DuplicateTreeError

    write_trees(
        tmp_path,
        sleep="""
        name: sleep
        root: {wait: 1}
    """,
    )
    with pytest.raises(DuplicateTreeError, match="tree name 'sleep' is already the actor sleep"):
        TreeHost(rt).load_folder(tmp_path)
    assert not rt.resolve("sleep").is_tree


def test_a_condition_under_a_reactive_parent_lets_its_sibling_finish(rt: Runtime, tmp_path: Path) -> None:
    # the guard is asked again on every tick (one a second); as a condition it answers
    # within the tick, so the running sibling is never halted
    write_trees(
        tmp_path,
        guarded="""
        name: guarded
        root:
          reactive_fallback:
            - condition: echo
              with: {value: false}
            - {do: block, with: {tag: work, seconds: 5}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path, max_period=1.0)
    assert rt.call("guarded") == {}
    assert rt.now() == pytest.approx(5.0)
    assert script.started == ["work"] and script.cancelled == []
    guard_states = {e[4] for e in rec.events if e[0] == "status" and e[2].endswith("echo")}
    assert "RUNNING" not in guard_states
    assert_clean(rt, host)


def test_the_same_guard_as_a_do_leaf_halts_its_sibling_on_every_tick(rt: Runtime, tmp_path: Path) -> None:
    # why condition: exists (a do: leaf is RUNNING for a tick, and the reactive parent
    # halts whatever ran after it)
    write_trees(
        tmp_path,
        restless="""
        name: restless
        root:
          timeout:
            seconds: 10
            child:
              reactive_fallback:
                - do: echo
                  with: {value: false}
                - {do: block, with: {tag: work, seconds: 5}}
    """,
    )
    host, script, rec = host_for(rt, tmp_path, max_period=1.0)
    with pytest.raises(ActorError, match="timed out after 10 s"):
        rt.call("restless")
    assert len(script.cancelled) >= 5
    assert_clean(rt, host)


def test_a_condition_holds_the_tick_until_it_answers_and_cancels_cleanly(rt: Runtime, tmp_path: Path) -> None:
    write_trees(
        tmp_path,
        slow_guard="""
        name: slow_guard
        root:
          sequence:
            - condition: block
              with: {tag: guard, seconds: 2}
              out: answer
            - condition: act
              with: {tag: stuck}
    """,
    )
    host, script, rec = host_for(rt, tmp_path)
    outcomes: list[Any] = []
    txn = rt.start("slow_guard", on_done=outcomes.append)
    deadline = time.monotonic() + 2
    while "stuck" not in script.started and time.monotonic() < deadline:
        time.sleep(0.001)
    assert rt.now() == pytest.approx(2.0)
    assert rec.ticks("slow_guard") == 1  # both answers came within the first tick
    txn.cancel("operator abort")
    while not outcomes and time.monotonic() < deadline:
        time.sleep(0.001)
    assert outcomes and outcomes[0].cancelled
    assert script.cancelled == ["stuck"]
    assert_clean(rt, host)
