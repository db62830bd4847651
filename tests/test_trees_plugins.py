"""Controls and decorators written in Python (bt_engine/trees/_plugins.py,
_plugin_nodes.py, nav2_nodes.py), tested as the built-ins are: tick tables (see
tests/tick_world.py), halting mid-run, load-time errors, trace and replay."""

from __future__ import annotations

from pathlib import Path
import pytest
from py_trees.common import Status

from bt_engine import Runtime, SubSystem, actor
from bt_engine.trees import (
    ControlNode,
    DecoratorNode,
    InputPort,
    MissionError,
    OutputPort,
    TreeHost,
    TreeLibrary,
    TraceRecorder,
    control_node,
    decorator_node,
    parse_mission,
    validate_mission,
)
from bt_tools.replay import replay
from bt_tools.show import ascii_tree
from bt_engine.trees.testing import FakeResolver, ScriptedActors
from tick_world import World


@control_node("FirstToSucceed", children=(2, None))
class FirstToSucceed(ControlNode):
    """Ticks every child each tick; succeeds when one does, fails when all have failed."""

    def on_tick(self) -> Status:
        statuses = [self.tick_child(child) for child in self.children]
        if Status.SUCCESS in statuses:
            return Status.SUCCESS
        return Status.FAILURE if all(s is Status.FAILURE for s in statuses) else Status.RUNNING


@decorator_node("Throttled")
class Throttled(DecoratorNode):
    """Asks an actor (in the background) for a limit, writes it scaled, then ticks the child."""

    ports = {
        "limits": InputPort(str, "act", "the actor asked for the limit", actor=True),
        "tag": InputPort(str, "limit", "its tag"),
        "scale": InputPort(float, 1.0, "multiplies the limit"),
        "limit": OutputPort(float, "the limit written"),
    }

    def on_start(self) -> None:
        self.call = self.start_actor(self.input("limits"), tag=self.input("tag"))

    def on_tick(self) -> Status:
        if not self.call.done:
            return Status.RUNNING
        if not self.call.succeeded:
            self.feedback_message = self.call.problem
            return Status.FAILURE
        self.output("limit", self.call.value * self.input("scale"))
        return self.tick_child()


@pytest.fixture(autouse=True)
def _close_runs(w: World):
    yield
    for run in w.host.live_runs():
        w.rt.run_on_hub(run.close)


# ---------------------------------------------------------------- tick tables


def test_round_robin_takes_turns_from_where_it_left_off(w: World) -> None:
    run = w.tree("""
        name: rr
        root:
          name: rr
          control: RoundRobin
          children:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
            - {name: c, do: act, with: {tag: c}}
    """)
    w.table(
        run,
        "rr a b c",
        [
            (None, "R", "R", "I", "I"),
            (w.fail("a"), "R", "F", "R", "I"),  # a failed: b's turn, in the same tick
            (w.finish("b"), "S", "F", "S", "I"),  # the first success succeeds
            (None, "R", "F", "S", "R"),  # ticked again: c's turn
            (w.fail("c"), "R", "R", "S", "F"),  # round and round: a
            (w.fail("a"), "R", "F", "R", "F"),
            (w.fail("b"), "F", "F", "F", "F"),  # all three failed in one round
        ],
    )
    assert w.script.started == ["a", "b", "c", "a", "b"]


def test_round_robin_starts_over_after_a_halt(w: World) -> None:
    run = w.tree(
        """
        name: rrh
        inputs: {go: bool}
        root:
          name: top
          reactive_sequence:
            - {name: go, check: go}
            - name: rr
              control: RoundRobin
              children:
                - {name: a, do: act, with: {tag: a}}
                - {name: b, do: act, with: {tag: b}}
    """,
        go=True,
    )
    w.table(
        run,
        "rr a b",
        [
            (None, "R", "R", "I"),
            (w.fail("a"), "R", "F", "R"),
            (w.write(run, "go", False), "I", "I", "I"),  # halted: b is cancelled
            (w.write(run, "go", True), "R", "R", "I"),  # starts over at a
        ],
    )
    assert w.script.cancelled == ["b"]


def test_a_control_written_in_python(w: World) -> None:
    run = w.tree("""
        name: fts
        root:
          name: fts
          control: FirstToSucceed
          children:
            - {name: a, do: act, with: {tag: a}}
            - {name: b, do: act, with: {tag: b}}
    """)
    w.table(
        run,
        "fts a b",
        [
            (None, "R", "R", "R"),
            (w.fail("a"), "R", "F", "R"),  # a restarted on the next tick
            (None, "R", "R", "R"),
            (w.finish("b"), "S", "I", "S"),  # a, still running, is halted by the base class
        ],
    )
    assert w.script.cancelled == ["a"]


def test_a_decorator_calls_an_actor_and_writes_the_blackboard(w: World) -> None:
    run = w.tree("""
        name: thr
        root:
          name: top
          sequence:
            - name: thr
              decorator: Throttled
              with: {scale: 2.0}
              out: {limit: speed}
              child: {name: drive, do: act, with: {tag: drive}}
            - {name: fast, check: speed == 1.0}
    """)
    w.table(
        run,
        "thr drive fast",
        [
            (None, "R", "I", "I"),  # waiting for the limit
            (w.finish("limit", 0.5), "R", "R", "I"),  # 0.5 * 2 written, the child runs
            (w.finish("drive"), "S", "S", "S"),
        ],
    )
    assert run.bb.get("speed") == 1.0


def test_halting_a_plugin_mid_run_leaves_no_transaction(w: World) -> None:
    run = w.tree(
        """
        name: halt
        inputs: {go: bool}
        root:
          name: top
          reactive_sequence:
            - {name: go, check: go}
            - name: thr
              decorator: Throttled
              child: {name: drive, do: act, with: {tag: drive}}
    """,
        go=True,
    )
    w.table(
        run,
        "thr drive",
        [
            (None, "R", "I"),
            (w.write(run, "go", False), "I", "I"),  # halted while its own call runs
            (w.write(run, "go", True), "R", "I"),
            (w.finish("limit", 1.0), "R", "R"),
            (w.write(run, "go", False), "I", "I"),  # halted while its child runs
        ],
    )
    assert w.script.cancelled == ["limit", "drive"]
    assert w.rt.transactions() == []


def test_goal_updated_controller_ticks_the_child_when_the_goal_changes(w: World) -> None:
    run = w.tree(
        """
        name: guc
        inputs: {goal: any}
        root:
          name: guc
          decorator: GoalUpdatedController
          child: {name: plan, do: act, with: {tag: plan}}
    """,
        goal={"x": 1},
    )
    w.table(
        run,
        "guc plan",
        [
            (None, "R", "R"),
            (w.finish("plan"), "S", "S"),
            (None, "R", "S"),  # same goal: not ticked
            (w.write(run, "goal", {"x": 2}), "R", "R"),  # a new goal: planned again
        ],
    )
    assert w.script.started == ["plan", "plan"]


class Robot(SubSystem):
    """A robot driving along x at 1 m/s (a step a quarter second), and a planner that
    notes where it plans."""

    def __init__(self) -> None:
        super().__init__()
        self.x = 0.0
        self.plans: list[float] = []

    @actor
    def where(self) -> tuple:
        return (self.x, 0.0, 0.0)

    @actor
    def plan(self) -> None:
        self.plans.append(round(self.x, 3))

    @actor
    def drive(self, to: float) -> None:
        while self.x < to - 1e-9:
            self.runtime.sleep(0.25)
            self.x += 0.25


def test_distance_controller_ticks_the_child_every_distance(rt: Runtime, tmp_path: Path) -> None:
    robot = rt.add_subsystem("robot", Robot)
    (tmp_path / "dc.yaml").write_text("""\
name: dc
root:
  pipeline_sequence:
    - decorator: DistanceController
      with: {distance: 1.0, pose_actor: where, poll_period: 0.1}
      child: {do: plan}
    - {do: drive, with: {to: 2.5}}
""")
    TreeHost(rt).load_folder(tmp_path)
    rt.call("dc")
    assert robot.plans == [0.0, 1.0, 2.0]  # at the start, then every metre
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_path_longer_on_approach_ticks_the_child_only_for_a_detour_near_the_goal(w: World) -> None:
    near = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]  # 2 m, under prox_len
    detour = [(0.0, 0.0), (0.0, 3.0), (2.0, 3.0), (2.0, 0.0)]  # 8 m to the same goal: > 2 x 2 m
    run = w.tree(
        """
        name: ploa
        inputs: {path: any}
        root:
          name: ploa
          decorator: PathLongerOnApproach
          with: {path: "{path}", prox_len: 3.0, length_factor: 2.0}
          child: {name: replan, do: act, with: {tag: replan}}
    """,
        path=near,
    )
    w.table(
        run,
        "ploa replan",
        [
            (None, "S", "I"),  # the first path: nothing to compare
            (None, "S", "I"),  # the same path
            (w.write(run, "path", detour), "R", "R"),  # a detour on approach
            (w.finish("replan"), "S", "I"),  # the child's success, then halted
            (w.write(run, "path", [(0.0, 0.0), (5.0, 5.0)]), "S", "I"),  # another goal: compared from now on
        ],
    )
    assert w.script.started == ["replan"]


def test_goal_updater_takes_the_newer_goal_its_actor_answers(rt: Runtime, tmp_path: Path) -> None:
    class Goals(SubSystem):
        newer: dict | None = None

        @actor
        def latest(self) -> dict | None:
            return self.newer

        @actor
        def follow(self, goal: dict) -> dict:
            return goal

    goals = rt.add_subsystem("goals", Goals)
    (tmp_path / "gu.yaml").write_text("""\
name: gu
inputs: {goal: {type: dict}}
outputs: [followed]
root:
  decorator: GoalUpdater
  with: {input_goal: "{goal}", updates: latest}
  out: {output_goal: current}
  child: {do: follow, with: {goal: "{current}"}, out: followed}
""")
    TreeHost(rt).load_folder(tmp_path)
    assert rt.call("gu", goal={"x": 1}) == {"followed": {"x": 1}}  # no update: the goal given
    goals.newer = {"x": 7}
    assert rt.call("gu", goal={"x": 1}) == {"followed": {"x": 7}}


class Cruiser(Robot):
    """The Robot at a speed of one's choice, noting when it plans."""

    speed = 1.0

    def __init__(self) -> None:
        super().__init__()
        self.plan_times: list[float] = []

    @actor
    def plan(self) -> None:
        self.plan_times.append(round(self.runtime.now(), 3))

    @actor
    def cruise(self, seconds: float) -> None:
        for _ in range(round(seconds / 0.25)):
            self.runtime.sleep(0.25)
            self.x += 0.25 * self.speed


@pytest.mark.parametrize(
    "speed, plans",
    [
        (1.0, [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]),  # 2 Hz at max_speed
        (0.0, [0.0, 0.5, 2.5]),  # the first period at max_rate, then 0.5 Hz standing still
    ],
)
def test_speed_controller_ticks_the_child_faster_the_faster_the_robot(
    rt: Runtime, tmp_path: Path, speed: float, plans: list[float]
) -> None:
    robot = rt.add_subsystem("robot", Cruiser)
    robot.speed = speed
    (tmp_path / "sc.yaml").write_text("""\
name: sc
root:
  pipeline_sequence:
    - decorator: SpeedController
      with: {min_rate: 0.5, max_rate: 2.0, min_speed: 0.0, max_speed: 1.0, pose_actor: where}
      child: {do: plan}
    - {do: cruise, with: {seconds: 3.0}}
""")
    TreeHost(rt).load_folder(tmp_path)
    rt.call("sc")
    assert robot.plan_times == plans
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_an_unset_port_fails_the_node_at_run_time(w: World) -> None:
    run = w.tree("""
        name: unset
        root:
          name: gu
          decorator: GoalUpdater
          child: {name: plan, do: act, with: {tag: plan}}
    """)
    w.table(run, "gu plan", [(None, "F", "I")])
    assert "port 'input_goal' of GoalUpdater is not set" in run.failure().reason


# ---------------------------------------------------------------- load time


@pytest.mark.parametrize(
    "body, where, message",
    [
        (
            "control: RoundRobbin\n  children: [{do: a}]",
            "3:12",
            "unknown control 'RoundRobbin' (did you mean 'RoundRobin'?)",
        ),
        ("decorator: RoundRobin\n  child: {do: a}", "3:14", "'RoundRobin' is a control node, expected control:"),
        (
            "control: FirstToSucceed\n  children: [{do: a}]",
            "4:13",
            "control 'FirstToSucceed' has 1 children, expected at least 2",
        ),
        (
            "decorator: DistanceController\n  with: {distnce: 2}\n  child: {do: a}",
            "4:19",
            "'distnce' is not a port of it (did you mean 'distance'?)",
        ),
        (
            "decorator: DistanceController\n  with: {distance: far}\n  child: {do: a}",
            "4:20",
            "port 'distance' of decorator 'DistanceController' expects a float, got str 'far'",
        ),
        (
            "decorator: GoalUpdater\n  with: {input_goal: 1}\n  out: {output: g}\n  child: {do: a}",
            "5:17",
            "has no output port 'output' (did you mean 'output_goal'?)",
        ),
        ("decorator: DistanceController\n  with: {pose_actor: wher}\n  child: {do: a}", "4:22", "unknown actor 'wher'"),
        (
            'decorator: GoalUpdater\n  with: {input_goal: "{goal}"}\n  child: {do: a}',
            "4:24",
            "blackboard key 'goal' is never written",
        ),
    ],
)
def test_plugin_errors_are_located(body: str, where: str, message: str) -> None:
    mission = parse_mission(f"name: bad\nroot:\n  {body}\n", "bad.yaml")
    errors = validate_mission(mission, FakeResolver(a=lambda: None, where=lambda: None), nodes=TreeLibrary().nodes)
    assert errors, body
    assert str(errors[0]).startswith(f"bad.yaml:{where}: "), str(errors[0])
    assert message in str(errors[0])


def test_a_plugin_is_drawn_with_its_ports() -> None:
    mission = parse_mission(
        "name: t\nroot:\n  decorator: GoalUpdater\n  with: {input_goal: 1}\n  out: {output_goal: g}\n  child: {do: a}\n"
    )
    assert "decorator GoalUpdater(input_goal=1, output_goal->g)" in ascii_tree(mission)


def test_a_host_takes_plugins_of_its_own(rt: Runtime, tmp_path: Path) -> None:
    class NotMarked(ControlNode):
        pass

    with pytest.raises(TypeError, match="not marked"):
        TreeHost(rt, nodes=[NotMarked])
    assert "FirstToSucceed" in TreeHost(rt, nodes=[FirstToSucceed]).nodes


def test_an_unknown_plugin_name_stops_the_load(rt: Runtime, tmp_path: Path) -> None:
    (tmp_path / "t.yaml").write_text("name: t\nroot:\n  control: Nope\n  children: [{wait: 1}]\n")
    with pytest.raises(MissionError, match="unknown control 'Nope'"):
        TreeHost(rt).load_folder(tmp_path)


# ---------------------------------------------------------------- trace and replay


PLUGGED = """\
name: plugged
inputs: {goal: {type: dict, default: {x: 1.0}}}
outputs: [speed]
root:
  name: plugged
  control: RoundRobin
  children:
    - name: first
      decorator: Throttled
      with: {limits: echo_limit, tag: x, scale: 2.0}
      out: {limit: speed}
      child:
        name: sub
        decorator: GoalUpdater
        with: {input_goal: "{goal}"}
        out: {output_goal: current}
        child: {name: slow, do: block, with: {tag: slow, seconds: 1.0}}
"""


class Limits(ScriptedActors):
    @actor
    def echo_limit(self, tag: str) -> float:
        self.runtime.sleep(0.5)
        return 0.25


def test_a_run_with_plugins_replays(tmp_path: Path) -> None:
    folder = tmp_path / "trees"
    folder.mkdir()
    (folder / "plugged.yaml").write_text(PLUGGED)
    trace = tmp_path / "run.jsonl"
    with Runtime() as rt:
        rt.add_subsystem("script", Limits)
        host = TreeHost(rt)
        host.load_folder(folder)
        with TraceRecorder(trace, host, tree="plugged"):
            assert rt.call("plugged") == {"speed": 0.5}
        assert rt.stats() == {"transactions": 0, "tasks": 0}
    text = trace.read_text()
    assert '"type":"call","run":1,"path":"plugged/first","call":1,"actor":"echo_limit"' in text
    assert '"nodes":{"RoundRobin":"bt_engine.trees.nav2_nodes","Throttled":"test_trees_plugins"' in text
    report = replay(trace, trees=folder)
    assert report.ok, str(report)
    (folder / "plugged.yaml").write_text(PLUGGED.replace("scale: 2.0", "scale: 3.0"))
    report = replay(trace, trees=folder)
    assert not report.ok and "speed" in str(report.divergence)
