"""Tick tables for the control nodes added for BehaviorTree.CPP and Nav2 trees:
resume_sequence, pipeline_sequence, if_then_else, while_do_else, recovery, counting
parallel, rate_controller, run_once and retry forever (see test_trees_ticks for the
table format)."""

from __future__ import annotations

import pytest

from bt_engine.trees import InvalidValueError, parse_mission
from tick_world import World


@pytest.fixture(autouse=True)
def _close_runs(w: World):
    """Runs driven tick by tick are closed here (their blackboard namespaces removed)."""
    yield
    for run in w.host.live_runs():
        w.rt.run_on_hub(run.close)


def test_resume_sequence_resumes_at_the_failed_child(w: World) -> None:
    run = w.tree("""
        name: rs
        root:
          name: rs
          resume_sequence:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "rs a b",
        [
            (None, "R", "R", "I"),
            (w.finish("a"), "R", "S", "R"),
            (w.fail("b"), "F", "S", "F"),
            (None, "R", "S", "R"),  # b again, a not restarted
            (w.finish("b"), "S", "S", "S"),
            (None, "R", "R", "I"),  # after a success it starts over
        ],
    )
    assert w.script.started == ["a", "b", "b", "a"]


def test_pipeline_sequence_keeps_earlier_children_ticking(w: World) -> None:
    run = w.tree("""
        name: ps
        root:
          name: ps
          pipeline_sequence:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "ps a b",
        [
            (None, "R", "R", "I"),
            (w.finish("a"), "R", "S", "R"),
            (None, "R", "R", "R"),  # a restarted alongside b
            (w.finish("a"), "R", "S", "R"),
            (w.finish("b"), "R", "R", "S"),  # a restarted, b done: the furthest is b, a runs
            (w.finish("a"), "S", "I", "I"),  # all succeeded in one tick (b re-ticked is restarted: not here)
        ][:4],
    )
    w.rt.run_on_hub(lambda: w.script.fail("b"))
    w.rt.run_on_hub(run.tick)
    assert run.status.name == "FAILURE"
    assert "a" in w.script.cancelled  # the running a was halted


def test_if_then_else_decides_once(w: World) -> None:
    run = w.tree("""
        name: ite
        root:
          name: ite
          if_then_else:
            - {name: cond, do: act, with: {tag: cond}}
            - {name: then, do: act, with: {tag: then}}
            - {name: else, do: act, with: {tag: else}}
    """)
    w.table(
        run,
        "ite cond then else",
        [
            (None, "R", "R", "I", "I"),
            (w.fail("cond"), "R", "F", "I", "R"),
            (None, "R", "F", "I", "R"),  # the condition is not ticked again
            (w.finish("else"), "S", "F", "I", "S"),
        ],
    )


def test_if_then_else_without_else_fails(w: World) -> None:
    run = w.tree("""
        name: it
        root:
          name: it
          if_then_else:
            - {name: cond, check: "false"}
            - {name: then, do: act, with: {tag: then}}
    """)
    w.table(run, "it cond then", [(None, "F", "F", "I")])


def test_while_do_else_switches_branch_when_the_condition_changes(w: World) -> None:
    run = w.tree("""
        name: wde
        inputs: {go: {type: bool, default: true}}
        root:
          name: wde
          while_do_else:
            - {name: cond, check: go}
            - {name: work, do: act, with: {tag: work}}
            - {name: idle, do: act, with: {tag: idle}}
    """)
    w.table(
        run,
        "wde cond work idle",
        [
            (None, "R", "S", "R", "I"),
            (w.write(run, "go", False), "R", "F", "I", "R"),
            (w.write(run, "go", True), "R", "S", "R", "I"),
            (w.finish("work"), "S", "S", "S", "I"),
        ],
    )
    assert w.script.cancelled == ["work", "idle"]


def test_recovery_retries_after_a_successful_recovery(w: World) -> None:
    run = w.tree("""
        name: rec
        root:
          name: rec
          recovery:
            retries: 2
            children:
              - {name: act, do: act, with: {tag: act}}
              - {name: fix, do: act, with: {tag: fix}}
    """)
    w.table(
        run,
        "rec act fix",
        [
            (None, "R", "R", "I"),
            (w.fail("act"), "R", "F", "R"),
            (w.finish("fix"), "R", "R", "S"),
            (w.fail("act"), "R", "F", "R"),
            (w.finish("fix"), "R", "R", "S"),
            (w.fail("act"), "F", "F", "S"),  # two recoveries used
        ],
    )


def test_recovery_fails_when_the_recovery_fails(w: World) -> None:
    run = w.tree("""
        name: rec2
        root:
          name: rec
          recovery: {children: [{name: act, do: act, with: {tag: act}}, {name: fix, do: act, with: {tag: fix}}]}
    """)
    w.table(
        run,
        "rec act fix",
        [
            (None, "R", "R", "I"),
            (w.fail("act"), "R", "F", "R"),
            (w.fail("fix"), "F", "F", "F"),
        ],
    )


def test_counting_parallel(w: World) -> None:
    run = w.tree("""
        name: par
        root:
          name: par
          parallel:
            success_count: 2
            failure_count: 2
            children:
              - {name: a, do: act, with: {tag: a}}
              - {name: b, do: act, with: {tag: b}}
              - {name: c, do: act, with: {tag: c}}
    """)
    w.table(
        run,
        "par a b c",
        [
            (None, "R", "R", "R", "R"),
            (w.fail("a"), "R", "F", "R", "R"),  # one failure is allowed
            (w.finish("b"), "R", "F", "S", "R"),
            (w.finish("c"), "S", "F", "S", "S"),
        ],
    )


def test_counting_parallel_fails_when_success_is_out_of_reach(w: World) -> None:
    run = w.tree("""
        name: par2
        root:
          name: par
          parallel:
            success_count: -1
            failure_count: 2
            children:
              - {name: a, do: act, with: {tag: a}}
              - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "par a b",
        [
            (None, "R", "R", "R"),
            (w.fail("a"), "F", "F", "I"),
        ],
    )
    assert w.script.cancelled == ["b"]


def test_rate_controller_ticks_the_child_once_per_period(w: World) -> None:
    run = w.tree("""
        name: rc
        root:
          name: ps
          pipeline_sequence:
            - name: rate
              rate_controller:
                hz: 0.5
                child: {name: plan, do: act, with: {tag: plan}}
            - {name: follow, do: act, with: {tag: follow}}
    """)
    w.table(
        run,
        "ps rate plan follow",
        [
            (None, "R", "R", "R", "I"),
            (w.finish("plan"), "R", "S", "S", "R"),
            (1.0, "R", "R", "S", "R"),  # within the period: the child is not ticked
            (1.0, "R", "R", "R", "R"),  # 2 s later: planned again while following
            (w.finish("plan"), "R", "S", "S", "R"),
            (w.finish("follow"), "S", "I", "I", "I"),
        ][:5],
    )
    assert w.script.started == ["plan", "follow", "plan"]


def test_run_once(w: World) -> None:
    run = w.tree("""
        name: once
        root:
          name: rep
          repeat:
            times: 3
            child:
              name: once
              run_once: {then: success, child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "rep once a",
        [
            (None, "R", "R", "R"),
            (w.fail("a"), "F", "F", "F"),
        ],
    )
    run2 = w.tree("""
        name: once2
        root:
          name: rep
          repeat:
            times: 3
            child: {name: once, run_once: {then: success, child: {name: a, do: act, with: {tag: a2}}}}
    """)
    w.table(
        run2,
        "rep once a",
        [
            (None, "R", "R", "R"),
            (w.finish("a2"), "R", "S", "S"),
            (None, "R", "S", "S"),  # not ticked again
            (None, "S", "S", "S"),
        ],
    )
    assert w.script.started.count("a2") == 1


def test_retry_forever(w: World) -> None:
    run = w.tree("""
        name: rf
        root:
          name: retry
          retry: {times: forever, child: {name: a, do: act, with: {tag: a}}}
    """)
    rows = []
    for _ in range(5):
        rows += [(w.fail("a"), "R", "I")]
    w.table(run, "retry a", [(None, "R", "R")] + rows[:0])
    for _ in range(5):
        w.rt.run_on_hub(lambda: w.script.fail("a"))
        w.rt.run_on_hub(run.tick)
        w.rt.run_on_hub(run.tick)
        assert run.status.name == "RUNNING"
    assert w.script.started.count("a") == 6


@pytest.mark.parametrize(
    "text, message",
    [
        ("if_then_else: [{check: a}]", "expected 2 or 3"),
        ("recovery: {children: [{check: a}]}", "expected 2: the action and its recovery"),
        ("parallel: {success_count: 4, children: [{check: a}, {check: a}]}", "expected an integer from 1 to 2"),
        ("parallel: {success_count: 1, policy: success_on_one, children: [{check: a}]}", "not both"),
        ("rate_controller: {hz: 0, child: {check: a}}", "hz is 0"),
        ("run_once: {then: skip, child: {check: a}}", "expected one of: same, success, failure"),
        ("recovery: {retries: -1, children: [{check: a}, {check: a}]}", "recovery retries is -1"),
    ],
)
def test_control_errors_are_located(text: str, message: str) -> None:
    with pytest.raises(InvalidValueError, match=message) as info:
        parse_mission(f"name: t\ninputs: {{a: bool}}\nroot:\n  {text}\n", "t.yaml")
    assert str(info.value).startswith("t.yaml:4:")
