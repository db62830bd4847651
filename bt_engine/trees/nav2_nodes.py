"""Nav2's control and decorator nodes that actorbt has no built-in for, written as
plugins (``_plugins``, ``_plugin_nodes``): each is registered under its Nav2 name, so
Nav2's trees import and run with them, and a mission names them as ``control:`` or
``decorator:``.

They keep Nav2's ports, so Nav2's node model describes them. What Nav2 reads from ROS
they ask an actor for, named by a port of their own: the robot's pose comes from the
actor ``pose_actor`` names (``get_pose`` by default, answering ``(x, y, yaw)``), and a
new goal for GoalUpdater from the one ``updates`` names. Nothing here knows a robot.

PipelineSequence, RecoveryNode, RateController and SingleTrigger are built-in mission
nodes (``pipeline_sequence``, ``recovery``, ``rate_controller``, ``run_once``).
"""

from __future__ import annotations

import math
from typing import Any

from py_trees.common import Status

from ._plugin_nodes import ControlNode, DecoratorNode
from ._plugins import InputPort, OutputPort, control_node, decorator_node
from ._poses import path_length, path_points, xy

__all__ = [
    "DistanceController",
    "GoalUpdatedController",
    "GoalUpdater",
    "PathLongerOnApproach",
    "RoundRobin",
    "SpeedController",
]

#: the actor that answers the robot's pose, unless a mission names another
POSE_ACTOR = "get_pose"

_POSE_PORTS = {
    "global_frame": InputPort(str, doc="the frame of the pose (Nav2's tf lookup); the pose actor answers in its own"),
    "robot_base_frame": InputPort(str, doc="the robot's base frame (Nav2's tf lookup)"),
    "pose_actor": InputPort(str, POSE_ACTOR, "the actor asked for the robot's pose, answering (x, y, ...)", actor=True),
}


def _pose(node: ControlNode | DecoratorNode) -> tuple[float, float]:
    return xy(node.ask(node.input("pose_actor")))


@control_node("RoundRobin")
class RoundRobin(ControlNode):
    """Nav2's RoundRobin: ticks one child at a time, taking turns. It starts where the
    last run left off (the child after the one that last finished); succeeds on the
    first success; a failure moves on to the next child, and when every child has
    failed in one round, the node fails. A halt starts it over at the first child."""

    def on_create(self) -> None:
        self.index = 0
        self.failed = 0

    def on_tick(self) -> Status:
        n = len(self.children)
        while self.failed < n:
            status = self.tick_child(self.index)
            if status is Status.RUNNING:
                return status
            self.index = (self.index + 1) % n
            if status is Status.SUCCESS:
                self.failed = 0
                return status
            self.failed += 1
        self.feedback_message = f"all {n} children failed in turn"
        self.on_create()  # Nav2 halts itself here: the next round starts at the first child
        return Status.FAILURE

    def on_halt(self) -> None:
        self.on_create()


@decorator_node("DistanceController")
class DistanceController(DecoratorNode):
    """Nav2's DistanceController: ticks its child when the node starts, then again each
    time the robot has travelled ``distance`` from where it was when the child last
    succeeded; in between it is RUNNING (checking the pose every ``poll_period``).
    A running child is ticked on every tick."""

    ports = {
        "distance": InputPort(float, 1.0, "the distance travelled that ticks the child again [m]"),
        **_POSE_PORTS,
        "poll_period": InputPort(float, 0.2, "how often the pose is checked while waiting [s]"),
    }

    def on_start(self) -> None:
        self.start = _pose(self)
        self.first = True

    def on_tick(self) -> Status:
        here = _pose(self)
        travelled = math.dist(self.start, here)
        distance = float(self.input("distance"))
        if self.first or self.child.status is Status.RUNNING or travelled >= distance:
            self.first = False
            status = self.tick_child()
            if status is Status.SUCCESS:
                self.start = _pose(self)
                self.wake_in(float(self.input("poll_period")))  # a pipeline ticks it again: measure then
            return status
        self.feedback_message = f"travelled {travelled:.2f} of {distance:g} m"
        self.wake_in(float(self.input("poll_period")))
        return Status.RUNNING


@decorator_node("SpeedController")
class SpeedController(DecoratorNode):
    """Nav2's SpeedController: ticks its child at a rate that follows the robot's speed,
    ``min_rate`` at ``min_speed`` or slower up to ``max_rate`` at ``max_speed`` or
    faster; at the first tick, and again at ``max_rate`` whenever the goal changes. A
    running child is ticked on every tick. The speed is measured from the pose
    ``pose_actor`` answers, over the last period."""

    ports = {
        "min_rate": InputPort(float, 0.1, "the rate at min_speed and below [Hz]"),
        "max_rate": InputPort(float, 1.0, "the rate at max_speed and above [Hz]"),
        "min_speed": InputPort(float, 0.0, "below this speed the child is ticked at min_rate [m/s]"),
        "max_speed": InputPort(float, 0.5, "above this speed the child is ticked at max_rate [m/s]"),
        "goal": InputPort(Any, "{goal}", "the goal; when it changes the rate starts over"),
        "goals": InputPort(Any, "{goals}", "the goals; when they change the rate starts over"),
        "pose_actor": _POSE_PORTS["pose_actor"],
    }

    def _goals(self) -> tuple[Any, Any]:
        return (
            self.input("goal") if self.has_input("goal") else None,
            self.input("goals") if self.has_input("goals") else None,
        )

    def _restart(self) -> None:
        self.period = 1.0 / float(self.input("max_rate"))
        self.since = self.now()
        self.where = _pose(self)
        self.first = True

    def on_start(self) -> None:
        self.goals = self._goals()
        self._restart()

    def on_tick(self) -> Status:
        goals = self._goals()
        if goals != self.goals:
            self.goals = goals
            self._restart()
        elapsed = self.now() - self.since
        if self.first or self.child.status is Status.RUNNING or elapsed >= self.period:
            self.first = False
            if elapsed >= self.period:
                here = _pose(self)
                self.period = 1.0 / self.rate(math.dist(self.where, here) / elapsed if elapsed > 0 else 0.0)
                self.since, self.where = self.now(), here
            status = self.tick_child()
            if status is Status.RUNNING:
                return status
            self.wake_in(self.period - (self.now() - self.since))
            return status
        self.feedback_message = f"next tick of the child in {self.period - elapsed:.3g} s"
        self.wake_in(self.period - elapsed)
        return Status.RUNNING

    def rate(self, speed: float) -> float:
        """The tick rate for a speed [Hz], between min_rate and max_rate."""
        lo_rate, hi_rate = float(self.input("min_rate")), float(self.input("max_rate"))
        lo_speed, hi_speed = float(self.input("min_speed")), float(self.input("max_speed"))
        span = hi_speed - lo_speed
        scaled = lo_rate + (speed - lo_speed) / span * (hi_rate - lo_rate) if span > 0 else hi_rate
        return max(lo_rate, min(hi_rate, scaled))


@decorator_node("GoalUpdater")
class GoalUpdater(DecoratorNode):
    """Nav2's GoalUpdater: on every tick, writes ``output_goal`` (the newest goal: what
    the ``updates`` actor answers, else ``input_goal``) and then ticks its child with
    the child's status. Nav2 takes the newer goal from a topic; here the actor that
    ``updates`` names is asked, and answers a goal or None (no update). Without
    ``updates``, ``input_goal`` passes through."""

    ports = {
        "input_goal": InputPort(Any, doc="the goal as it was given"),
        "output_goal": OutputPort(Any, "the goal to use: the newest update, else input_goal"),
        "updates": InputPort(str, doc="the actor asked for a newer goal (answers a goal or None)", actor=True),
    }

    def on_tick(self) -> Status:
        goal = self.input("input_goal")
        if self.has_input("updates"):
            newer = self.ask(self.input("updates"))
            if newer is not None:
                goal = newer
        self.output("output_goal", goal)
        return self.tick_child()


@decorator_node("GoalUpdatedController")
class GoalUpdatedController(DecoratorNode):
    """Nav2's GoalUpdatedController: ticks its child when the node starts and whenever
    ``goal`` or ``goals`` has changed since; a running child is ticked on every tick.
    Otherwise it is RUNNING without ticking the child."""

    ports = {
        "goal": InputPort(Any, "{goal}", "the goal to watch"),
        "goals": InputPort(Any, "{goals}", "the goals to watch"),
    }

    def _goals(self) -> tuple[Any, Any]:
        return (
            self.input("goal") if self.has_input("goal") else None,
            self.input("goals") if self.has_input("goals") else None,
        )

    def on_start(self) -> None:
        self.goals = self._goals()
        self.updated = True

    def on_tick(self) -> Status:
        goals = self._goals()
        if goals != self.goals:
            self.goals = goals
            self.updated = True
        if self.child.status is Status.RUNNING or self.updated:
            self.updated = False
            return self.tick_child()
        self.feedback_message = "the goal has not changed"
        return Status.RUNNING


@decorator_node("PathLongerOnApproach")
class PathLongerOnApproach(DecoratorNode):
    """Nav2's PathLongerOnApproach: ticks its child only when a new path to the same goal
    is ``length_factor`` times longer than the previous one while the previous one was
    shorter than ``prox_len`` (the robot is near the goal); otherwise it succeeds
    without ticking it."""

    ports = {
        "path": InputPort(Any, doc="the newest path"),
        "prox_len": InputPort(float, 3.0, "the previous path is shorter than this near the goal [m]"),
        "length_factor": InputPort(float, 2.0, "how many times longer the new path must be"),
    }

    def on_create(self) -> None:
        self.old: list[tuple[float, float]] = []
        self.first = True

    def on_tick(self) -> Status:
        new = path_points(self.input("path"))
        old = self.old
        if not self.first and (not old or not new or old[-1] != new[-1]):
            self.first = True  # another goal: compare from now on
        longer = (
            new != old
            and bool(old)
            and bool(new)
            and old[-1] == new[-1]
            and path_length(old) < float(self.input("prox_len"))
            and path_length(new) > float(self.input("length_factor")) * path_length(old)
        )
        if longer and not self.first:
            status = self.tick_child()
            if status is not Status.RUNNING:
                self.old = new
                self.halt_child()
            return status
        self.old = new
        self.first = False
        return Status.SUCCESS
