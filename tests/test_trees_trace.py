"""Trace recording, headless replay (no actors loaded), divergence reports, plots."""

from __future__ import annotations

import dataclasses
import json
import logging
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest

from bt_engine import ActorError, Runtime, SubSystem, actor
from bt_engine.trees import TreeHost
from bt_tools.plot import plot_trace
from bt_tools.replay import ReplayError, read_trace, replay
from bt_engine.trees._trace import TraceRecorder, to_json
from bt_engine.trees.testing import ScriptedActors

REPO = Path(__file__).resolve().parents[1]
REPLAYS = sorted((REPO / "tests" / "replays").glob("*.jsonl"))

MISSION = """\
name: mission
inputs:
  target: {type: str, default: can}
  limit: {type: float, default: 2.0}
outputs: [result]
root:
  name: mission
  sequence:
    - name: find
      retry: {times: 3, child: {do: flaky, with: {tag: find, failures: 1}}}
    - name: reach
      selector:
        - timeout: {seconds: "{limit}", child: {name: slow, do: block, with: {tag: slow, seconds: 5}}}
        - {name: fast, do: block, with: {tag: fast, seconds: 1}}
    - {name: sub, do: helper, with: {value: "{target}"}, out: got}
    - set: {result: "{got.echoed}"}
    - {name: verify, check: result == "can"}
"""
HELPER = """\
name: helper
inputs: {value: any}
outputs: [echoed]
root:
  sequence:
    - {do: echo, with: {value: "{value}"}, out: echoed}
    - wait: 0.25
"""


def record(folder: Path, trace: Path, tree: str = "mission", **inputs: object) -> object:
    """Run ``tree`` with the scripted actors and record it; returns the result (or the error)."""
    with Runtime() as rt:
        rt.add_subsystem("script", ScriptedActors)
        host = TreeHost(rt)
        host.load_folder(folder)
        with TraceRecorder(trace, host, tree=tree, inputs=inputs):
            try:
                return rt.call(tree, **inputs)
            except ActorError as exc:
                return exc


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    trees = tmp_path / "trees"
    trees.mkdir()
    (trees / "mission.yaml").write_text(MISSION)
    (trees / "helper.yaml").write_text(HELPER)
    return trees


@pytest.mark.parametrize("trace", REPLAYS, ids=[p.stem for p in REPLAYS])
def test_recorded_runs_in_tests_replays_still_replay(trace: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    report = replay(trace)
    assert report.ok, str(report)
    assert report.compared > 20


def test_record_then_replay_round_trip(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    assert record(folder, trace) == {"result": "can"}
    report = replay(trace, trees=folder)
    assert report.ok, str(report)
    assert report.notes == []
    header, events = read_trace(trace)
    assert header["tree"] == "mission" and header["inputs"] == {}
    assert set(header["trees"]) == {"mission", "helper"}
    assert header["versions"]["py_trees"] == "2.6.0"
    kinds = {e["type"] for e in events}
    assert {"run", "tick", "status", "call", "return", "write", "end"} <= kinds
    cancelled = [e for e in events if e["type"] == "return" and e["state"] == "cancelled"]
    assert [e["actor"] for e in cancelled] == ["block"]  # the slow path, halted by the timeout


def test_a_failed_run_replays_too(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "fail.jsonl"
    outcome = record(folder, trace, target="bottle")
    assert isinstance(outcome, ActorError) and "verify" in str(outcome)
    report = replay(trace, trees=folder)
    assert report.ok, str(report)
    assert read_trace(trace)[1][-1]["status"] == "FAILURE"


def test_replay_detects_an_edited_tree(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    path = folder / "mission.yaml"
    path.write_text(path.read_text().replace('result == "can"', 'result == "bottle"'))
    report = replay(trace, trees=folder)
    assert not report.ok
    assert report.notes == [f"tree mission ({path}) changed since the recording"]
    # the edited check itself, told before the mission it ends
    assert str(report.divergence) == (
        "first divergence at event 57: expected [t=3.250s run 1] status of mission/verify: INVALID -> SUCCESS, "
        "got [t=3.250s run 1] status of mission/verify: INVALID -> FAILURE"
    )


def test_replay_detects_changed_actor_arguments_in_a_subtree(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    helper = folder / "helper.yaml"
    helper.write_text(helper.read_text().replace('value: "{value}"', "value: can"))
    report = replay(trace, trees=folder)
    # Same value at run time, but a literal now: the call still matches. Change timing instead.
    assert report.ok
    helper.write_text(helper.read_text().replace("wait: 0.25", "wait: 0.5"))
    report = replay(trace, trees=folder)
    assert not report.ok
    assert "run 2" in str(report.divergence) and "wait 0.5s" in str(report.divergence)


def test_replay_reports_a_changed_call(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    path = folder / "mission.yaml"
    path.write_text(path.read_text().replace("tag: fast, seconds: 1", "tag: fast, seconds: 2"))
    report = replay(trace, trees=folder)
    assert not report.ok
    assert "call #" in str(report.divergence) and 'block(tag="fast", seconds=2)' in str(report.divergence)


def test_replay_needs_the_tree_files(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ReplayError, match="tree 'mission' not found"):
        replay(trace, trees=empty)


def test_replay_finds_trees_next_to_the_trace(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    moved = tmp_path / "moved"
    moved.mkdir()
    shutil.copy(trace, moved / "run.jsonl")
    for f in folder.glob("*.yaml"):
        shutil.copy(f, moved / f.name)
    shutil.rmtree(folder)
    assert replay(moved / "run.jsonl").ok


def test_bad_trace_files(tmp_path: Path) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"type": "header", "format": "actorbt-trace", "version": 1}\n{not json\n')
    with pytest.raises(ReplayError, match=r"bad\.jsonl:2:2: not JSON"):
        read_trace(bad)
    bad.write_text('{"hello": 1}\n')
    with pytest.raises(ReplayError, match="not an actorbt trace"):
        read_trace(bad)
    with pytest.raises(ReplayError, match="cannot read trace"):
        read_trace(tmp_path / "missing.jsonl")


def test_recorder_is_the_runtime_recorder_service(folder: Path, tmp_path: Path) -> None:
    class Talker(SubSystem):
        @actor
        def talk(self) -> str:
            logging.getLogger("actorbt.test").warning("hello from %s", "talk")
            return "ok"

    (folder / "talky.yaml").write_text("name: talky\nroot: {do: talk, out: said}\n")
    trace = tmp_path / "talky.jsonl"
    with Runtime() as rt:
        rt.add_subsystem("script", ScriptedActors)
        rt.add_subsystem("talker", Talker)
        host = TreeHost(rt)
        host.load_folder(folder)
        before = rt.recorder
        with TraceRecorder(trace, host, tree="talky", transactions=True):
            assert rt.recorder is not before
            rt.recorder.emit({"type": "note", "text": "from the outside"})
            rt.call("talky")
        assert rt.recorder is before
    _, events = read_trace(trace)
    assert {"type": "note", "text": "from the outside", "t": 0.0} in events
    assert any(e["type"] == "log" and e["msg"] == "hello from talk" for e in events)
    txns = [(e["phase"], e["actor"]) for e in events if e["type"] == "txn"]
    assert ("start", "talky") in txns and ("start", "talker.talk") in txns and ("end", "talky") in txns
    assert replay(trace, trees=folder).ok  # log and txn events are not compared


def test_values_become_json() -> None:
    @dataclasses.dataclass
    class Grasp:
        width: float
        pose: tuple

    class Opaque:
        def __repr__(self) -> str:
            return "<opaque>"

    value = {
        "g": Grasp(0.02, (1, 2)),
        "err": ValueError("bad"),
        "o": Opaque(),
        "nan": float("nan"),
        "arr": np.arange(3),
        5: {1, 2} and [1],
    }
    out = to_json(value)
    json.dumps(out)
    assert out["g"] == {"__type__": Grasp.__qualname__, "width": 0.02, "pose": [1, 2]}
    assert out["err"] == {"__error__": "ValueError", "message": "bad"}
    assert out["o"] == {"__repr__": "<opaque>"}
    assert out["nan"] == {"__float__": "nan"}
    assert out["arr"] == [0, 1, 2]
    assert out["5"] == [1]


def test_ros_messages_become_json() -> None:
    from geometry_msgs.msg import Twist

    msg = Twist()
    msg.linear.x = 0.5
    out = to_json(msg)
    assert out["__type__"] == "geometry_msgs.msg._twist.Twist"
    assert out["linear"]["x"] == 0.5


def test_plot_draws_a_timeline(folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    out = plot_trace(trace, tmp_path / "timeline.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# -- every way in replays (issue cli-dx 6): run --record, a call nested in another actor,
# TraceRecorder around rt.call; on the virtual and the wall clock. `serve` goals are in
# tests/test_ros_server.py.

NAP = """\
name: nap
inputs: {tag: {type: str, default: a}}
outputs: [said]
root:
  sequence:
    - {name: first, do: sleep, with: {seconds: 0.05}}
    - {name: say, do: echo, with: {value: "{tag}"}, out: said}
    - {name: pause, wait: 0.03}
    - {name: last, do: sleep, with: {seconds: 0.02}}
"""


class Caller(SubSystem):
    @actor
    def outer(self, tag: str = "a") -> object:
        """Calls the tree from inside another actor's transaction."""
        self.run_actor("sleep", 0.01)
        return self.run_actor("nap", tag=tag)


@pytest.fixture
def nap_folder(tmp_path: Path) -> Path:
    trees = tmp_path / "trees"
    trees.mkdir()
    (trees / "nap.yaml").write_text(NAP)
    return trees


@pytest.mark.parametrize("clock", ["virtual", "wall"])
def test_actorbt_run_record_replays(
    nap_folder: Path, tmp_path: Path, clock: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from bt_cli.main import main

    config = tmp_path / "actorbt.yaml"
    config.write_text("subsystems: {script: bt_engine.trees.testing:ScriptedActors}\ntrees: trees\nworld: null\n")
    monkeypatch.chdir(tmp_path)
    trace = tmp_path / "run.jsonl"
    assert (
        main(
            [
                "--config",
                str(config),
                "run",
                "nap",
                "--arg",
                "tag=b",
                "--quiet",
                "--json",
                "--record",
                str(trace),
                "--clock",
                clock,
            ]
        )
        == 0
    )
    assert json.loads(capsys.readouterr().out) == {"said": "b"}
    assert read_trace(trace)[0]["clock"] == clock
    assert main(["replay", str(trace)]) == 0
    out = capsys.readouterr().out
    assert "replay of nap: OK" in out, out


@pytest.mark.parametrize("clock", ["virtual", "wall"])
@pytest.mark.parametrize("way", ["python", "nested"])
def test_a_recorder_around_rt_call_replays(nap_folder: Path, tmp_path: Path, clock: str, way: str) -> None:
    """Python: TraceRecorder around rt.call(tree), opened well before the tree starts;
    nested: the tree called by another actor (as `actorbt call outer` would)."""
    trace = tmp_path / "run.jsonl"
    with Runtime(clock=clock) as rt:
        rt.add_subsystem("script", ScriptedActors)
        rt.add_subsystem("caller", Caller)
        host = TreeHost(rt)
        host.load_folder(nap_folder)
        with TraceRecorder(trace, host, tree="nap", inputs={"tag": "b"}):
            rt.call("sleep", 0.1)  # the run starts 0.1 s after the recording
            if way == "python":
                assert rt.call("nap", tag="b") == {"said": "b"}
            else:
                assert rt.call("caller.outer", tag="b") == {"said": "b"}
    header, events = read_trace(trace)
    assert header["clock"] == clock
    assert events[0]["t"] >= 0.1
    report = replay(trace, trees=nap_folder)
    assert report.ok, str(report)
    assert report.compared > 10


def test_replay_times_are_relative_to_the_run_start(nap_folder: Path, tmp_path: Path) -> None:
    """A virtual-clock recording is compared exactly, from the run's start: a changed
    wait shows, and the report prints times from the run's start."""
    trace = tmp_path / "run.jsonl"
    with Runtime() as rt:
        rt.add_subsystem("script", ScriptedActors)
        host = TreeHost(rt)
        host.load_folder(nap_folder)
        with TraceRecorder(trace, host, tree="nap"):
            rt.call("sleep", 5.0)
            rt.call("nap")
    path = nap_folder / "nap.yaml"
    path.write_text(NAP.replace("pause, wait: 0.03", "pause, wait: 0.04"))
    report = replay(trace, trees=nap_folder)
    assert not report.ok
    assert "[t=0.080s run 1]" in str(report.divergence), str(report)
    assert "t=5." not in str(report.divergence)


def test_wall_clock_recordings_allow_jitter_but_not_a_changed_wait(nap_folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    with Runtime(clock="wall") as rt:
        rt.add_subsystem("script", ScriptedActors)
        host = TreeHost(rt)
        host.load_folder(nap_folder)
        with TraceRecorder(trace, host, tree="nap"):
            rt.call("nap")
    # jitter: every recorded time moved by up to 50 ms (more than the wall tolerance allows
    # in total, less than it allows between two events)
    lines = trace.read_text().splitlines()
    shifted = [lines[0]]
    for i, line in enumerate(lines[1:]):
        e = json.loads(line)
        e["t"] += 0.05 * (i % 2)
        shifted.append(json.dumps(e))
    jittery = tmp_path / "jittery.jsonl"
    jittery.write_text("\n".join(shifted) + "\n")
    assert replay(jittery, trees=nap_folder).ok
    (nap_folder / "nap.yaml").write_text(NAP.replace("pause, wait: 0.03", "pause, wait: 0.5"))
    report = replay(trace, trees=nap_folder)
    assert not report.ok, str(report)
    assert "tick 4, got [t=0.55" in str(report.divergence), str(report)  # the tick after the pause


def test_a_recorder_that_follows_a_transaction_skips_other_runs(nap_folder: Path, tmp_path: Path) -> None:
    trace = tmp_path / "run.jsonl"
    with Runtime() as rt:
        rt.add_subsystem("script", ScriptedActors)
        host = TreeHost(rt)
        host.load_folder(nap_folder)
        with TraceRecorder(trace, host, tree="nap", inputs={"tag": "b"}, transactions=True) as rec:
            done = [threading.Event(), threading.Event()]

            def start() -> None:
                mine = rt.start("nap", tag="b", on_done=lambda _: done[0].set())
                rec.follow(mine)
                rt.start("nap", tag="other", on_done=lambda _: done[1].set())

            rt.run_on_hub(start)
            assert done[0].wait(10) and done[1].wait(10)
    _, events = read_trace(trace)
    assert {e["run"] for e in events if "run" in e} == {1}
    assert not any(e.get("value") == "other" for e in events)
    assert replay(trace, trees=nap_folder).ok


def test_a_recording_in_the_old_order_still_replays(folder: Path, tmp_path: Path) -> None:
    """Recordings made before a tick's changes were told children first (a parent's end
    before its children's) replay: within one tick, the order of status changes is free."""
    import json

    trace = tmp_path / "run.jsonl"
    record(folder, trace)
    lines = trace.read_text().splitlines()
    header, events = lines[0], [json.loads(line) for line in lines[1:]]
    # reverse every batch of status changes of one run at one time
    out, batch = [], []
    for e in events + [{"type": "end-of-test"}]:
        if batch and not (
            e.get("type") == "status" and e.get("run") == batch[0]["run"] and e.get("t") == batch[0]["t"]
        ):
            out += batch[::-1]
            batch = []
        (batch if e.get("type") == "status" else out).append(e)
    old = tmp_path / "old.jsonl"
    old.write_text("\n".join([header] + [json.dumps(e) for e in out[:-1]]) + "\n")
    assert out[:-1] != events
    report = replay(old, trees=folder)
    assert report.ok, str(report)
