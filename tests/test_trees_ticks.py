"""Tick-by-tick status tables for every composite, decorator and leaf, with scripted
actors (``act(tag)`` runs until the test finishes it) and a manual clock.

Columns are node names. Each row is what the test does before the tick (an action on
the hub, a number of seconds passing, or None), then the statuses after the tick:
R running, S success, F failure, I invalid (not ticked, or halted)."""

from __future__ import annotations


from tick_world import World


def test_sequence_has_memory(w: World) -> None:
    run = w.tree("""
        name: seq
        root:
          name: seq
          sequence:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
            - {name: c, do: act, with: {tag: c}}
    """)
    w.table(
        run,
        "seq a b c",
        [
            (None, "R", "R", "I", "I"),
            (w.finish("a"), "R", "S", "R", "I"),
            (None, "R", "S", "R", "I"),
            (w.fail("b"), "F", "S", "F", "I"),
        ],
    )
    assert w.script.started == ["a", "b"]  # a was not restarted while b ran


def test_reactive_sequence_halts_the_running_child_when_a_condition_fails(w: World) -> None:
    run = w.tree("""
        name: rseq
        inputs: {ok: {type: bool, default: true}}
        root:
          name: rseq
          reactive_sequence:
            - {name: guard, check: ok}
            - {name: a, do: act, with: {tag: a}}
    """)
    w.table(
        run,
        "rseq guard a",
        [
            (None, "R", "S", "R"),
            (None, "R", "S", "R"),
            (w.write(run, "ok", False), "F", "F", "I"),
        ],
    )
    assert w.script.cancelled == ["a"]


def test_selector_has_memory(w: World) -> None:
    run = w.tree("""
        name: sel
        root:
          name: sel
          selector:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "sel a b",
        [
            (None, "R", "R", "I"),
            (w.fail("a"), "R", "F", "R"),
            (None, "R", "I", "R"),  # py_trees resets the skipped child
            (w.finish("b"), "S", "I", "S"),
        ],
    )
    assert w.script.started == ["a", "b"]  # a was not retried while b ran


def test_fallback_is_selector_and_fails_when_all_fail(w: World) -> None:
    run = w.tree("""
        name: fb
        root:
          name: fb
          fallback:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, check: "false"}
    """)
    w.table(
        run,
        "fb a b",
        [
            (None, "R", "R", "I"),
            (w.fail("a"), "F", "F", "F"),
        ],
    )


def test_reactive_selector_lets_a_higher_priority_child_take_over(w: World) -> None:
    run = w.tree("""
        name: rsel
        inputs: {done: {type: bool, default: false}}
        root:
          name: rsel
          reactive_selector:
            - {name: guard, check: done}
            - {name: a, do: act, with: {tag: a}}
    """)
    w.table(
        run,
        "rsel guard a",
        [
            (None, "R", "F", "R"),
            (w.write(run, "done", True), "S", "S", "I"),
        ],
    )
    assert w.script.cancelled == ["a"]


def test_parallel_success_on_all(w: World) -> None:
    run = w.tree("""
        name: par
        root:
          name: par
          parallel:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "par a b",
        [
            (None, "R", "R", "R"),
            (w.finish("b"), "R", "R", "S"),
            (None, "R", "R", "S"),
            (w.finish("a"), "S", "S", "S"),
        ],
    )
    assert w.script.started == ["a", "b"]  # b was not restarted after it succeeded


def test_parallel_fails_on_the_first_failure_and_halts_the_rest(w: World) -> None:
    run = w.tree("""
        name: parf
        root:
          name: par
          parallel:
            policy: success_on_all
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


def test_parallel_success_on_one(w: World) -> None:
    run = w.tree("""
        name: par1
        root:
          name: par
          parallel:
            policy: success_on_one
            children:
              - {name: a, do: act, with: {tag: a}}
              - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "par a b",
        [
            (None, "R", "R", "R"),
            (w.finish("b"), "S", "I", "S"),
        ],
    )
    assert w.script.cancelled == ["a"]


def test_parallel_success_on_selected(w: World) -> None:
    run = w.tree("""
        name: parsel
        root:
          name: par
          parallel:
            policy: success_on_selected
            selected: [a, c]
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
            (w.finish("b"), "R", "R", "S", "R"),
            (w.finish("a"), "R", "S", "S", "R"),
            (w.finish("c"), "S", "S", "S", "S"),
        ],
    )


def test_retry_restarts_the_child_until_attempts_run_out(w: World) -> None:
    run = w.tree("""
        name: retry
        root:
          name: retry
          retry:
            times: 3
            child: {name: a, do: act, with: {tag: a}}
    """)
    w.table(
        run,
        "retry a",
        [
            (None, "R", "R"),
            (w.fail("a"), "R", "F"),  # attempt 1 failed; the child restarts next tick
            (None, "R", "R"),
            (w.fail("a"), "R", "F"),
            (None, "R", "R"),
            (w.fail("a"), "F", "F"),  # attempt 3 failed: give up
        ],
    )
    assert w.script.started == ["a", "a", "a"]


def test_retry_succeeds_with_the_child(w: World) -> None:
    run = w.tree("""
        name: retry2
        root:
          name: retry
          retry: {times: 3, child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "retry a",
        [
            (None, "R", "R"),
            (w.fail("a"), "R", "F"),
            (None, "R", "R"),
            (w.finish("a"), "S", "S"),
        ],
    )


def test_repeat_counts_successes_and_stops_on_failure(w: World) -> None:
    run = w.tree("""
        name: repeat
        inputs: {n: {type: int, default: 2}}
        root:
          name: rep
          repeat: {times: "{n}", child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "rep a",
        [
            (None, "R", "R"),
            (w.finish("a"), "R", "S"),
            (None, "R", "R"),
            (w.finish("a"), "S", "S"),
        ],
    )
    run = w.tree("""
        name: repeat_fail
        root:
          name: rep
          repeat: {child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "rep a",
        [
            (None, "R", "R"),
            (w.finish("a"), "R", "S"),
            (None, "R", "R"),
            (w.fail("a"), "F", "F"),
        ],
    )


def test_timeout_halts_the_child_at_the_deadline(w: World) -> None:
    run = w.tree("""
        name: timeout
        root:
          name: to
          timeout: {seconds: 5, child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "to a",
        [
            (None, "R", "R"),
            (4.9, "R", "R"),
            (0.1, "F", "I"),
        ],
    )
    assert w.script.cancelled == ["a"]
    assert "timed out" in run.failure().reason


def test_timeout_passes_through_an_early_result(w: World) -> None:
    run = w.tree("""
        name: timeout_ok
        root:
          name: to
          timeout: {seconds: 5, child: {name: a, do: act, with: {tag: a}}}
    """)
    w.table(
        run,
        "to a",
        [
            (None, "R", "R"),
            (w.finish("a"), "S", "S"),
            (10, "R", "R"),  # the root restarts; the deadline is new
        ],
    )


def test_invert_force_success_force_failure(w: World) -> None:
    run = w.tree("""
        name: decos
        root:
          name: par
          parallel:
            - {name: inv, invert: {name: a, do: act, with: {tag: a}}}
            - {name: fs, force_success: {name: b, do: act, with: {tag: b}}}
            - {name: ff, force_failure: {name: c, check: "true"}}
    """)
    w.table(
        run,
        "par inv a fs b ff c",
        [
            (None, "F", "I", "I", "I", "I", "F", "S"),
        ],
    )
    run = w.tree("""
        name: decos2
        root:
          name: seq
          sequence:
            - {name: inv, invert: {name: a, do: act, with: {tag: a}}}
            - {name: fs, force_success: {name: b, do: act, with: {tag: b}}}
    """)
    w.table(
        run,
        "seq inv a fs b",
        [
            (None, "R", "R", "R", "I", "I"),
            (w.fail("a"), "R", "S", "F", "R", "R"),
            (w.fail("b"), "S", "S", "F", "S", "F"),
        ],
    )


def test_wait_runs_on_the_runtime_clock(w: World) -> None:
    run = w.tree("""
        name: wait
        inputs: {s: {type: float, default: 2}}
        root:
          name: seq
          sequence:
            - {name: w, wait: "{s}"}
            - {name: c, check: "true"}
    """)
    w.table(
        run,
        "seq w c",
        [
            (None, "R", "R", "I"),
            (1.0, "R", "R", "I"),
            (1.0, "S", "S", "S"),
        ],
    )


def test_actor_leaf_outcomes_set_and_check(w: World) -> None:
    run = w.tree("""
        name: leaves
        root:
          name: seq
          sequence:
            - {name: a, do: act, with: {tag: a}, out: got}
            - {name: s, set: {copy: "{got}", fixed: [1, 2]}}
            - {name: c, check: "copy.kind == 'can' and 2 in fixed"}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "seq a s c b",
        [
            (None, "R", "R", "I", "I", "I"),
            (w.finish("a", {"kind": "can"}), "R", "S", "S", "S", "R"),
            (w.finish("b", False), "F", "S", "S", "S", "F"),
        ],
    )
    assert run.bb.get("copy") == {"kind": "can"}
    failure = run.failure()
    assert failure.node_path == "seq/b" and "returned False" in failure.reason


def test_actor_exception_fails_the_leaf_with_the_error(w: World) -> None:
    run = w.tree("""
        name: boom
        root: {name: a, do: act, with: {tag: a}}
    """)
    w.table(run, "a", [(None, "R"), (w.fail("a"), "F")])
    assert "RuntimeError: a failed" in run.failure().reason


def test_check_on_an_unset_key_fails_with_a_reason(w: World) -> None:
    run = w.tree("""
        name: unset
        root:
          name: sel
          selector:
            - {name: a, do: act, with: {tag: a}, out: x}
            - {name: c, check: x > 1}
    """)
    w.table(run, "sel a c", [(None, "R", "R", "I"), (w.fail("a"), "F", "F", "F")])
    assert "blackboard key 'x' is not set" in run.failure().reason
