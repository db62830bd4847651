"""The simulated arm and gripper controllers, as ros2_control serves them on a TurtleBot3 +
OpenManipulator-X: /arm_controller/follow_joint_trajectory and
/gripper_controller/gripper_cmd on the bus, on open_floor under the virtual clock."""

from __future__ import annotations

import math

import pytest
from builtin_interfaces.msg import Duration, Time
from control_msgs.action import FollowJointTrajectory, GripperCommand
from control_msgs.msg import GripperCommand as GripperCommandMsg
from control_msgs.msg import JointTolerance
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bt_engine import ActorError, Runtime, SubSystem
from bt_engine.bus.actions import STATUS_ABORTED, STATUS_CANCELED, STATUS_SUCCEEDED, ActionGoalError, ServerGoal
from sim import SimWorld
from sim.actuators import GRIPPER_POSITION_CLOSED, GRIPPER_POSITION_OPEN, gripper_opening, gripper_position
from sim.controllers import ARM_ACTION, GRIPPER_ACTION, PREEMPTED

ARM = ["joint1", "joint2", "joint3", "joint4"]
R = FollowJointTrajectory.Result
START = [0.0, -1.0, 0.3, 0.7]


def _dur(t: float) -> Duration:
    return Duration(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))


def trajectory(*points, names=ARM) -> JointTrajectory:
    """points: (t, positions) or (t, positions, velocities)."""
    msg = JointTrajectory()
    msg.joint_names = list(names)
    for t, q, *v in points:
        pt = JointTrajectoryPoint(positions=[float(x) for x in q], time_from_start=_dur(t))
        if v:
            pt.velocities = [float(x) for x in v[0]]
        msg.points.append(pt)
    return msg


def arm_goal(traj: JointTrajectory, tolerance: float = 0.0, settle: float = 0.0):
    goal = FollowJointTrajectory.Goal(trajectory=traj)
    if tolerance:
        goal.goal_tolerance = [JointTolerance(name=n, position=tolerance) for n in ARM]
    goal.goal_time_tolerance = _dur(settle)
    return goal


class Clients(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.register_action("arm", FollowJointTrajectory, ARM_ACTION)
        self.register_action("grip", GripperCommand, GRIPPER_ACTION)


class Probe:
    """A goal sent straight to a server, seeing what a ROS client would: every feedback,
    the status and the result (the local client actor keeps only the outcome)."""

    def __init__(self, rt, server, request) -> None:
        self.feedback: list = []
        self.status = None
        self.result = None
        self.ended_at = None

        def finish(status, result):
            self.status, self.result, self.ended_at = status, result, rt.now()

        def send():
            self.goal = ServerGoal(
                server.name, server.action_type, request, finish, lambda fb: self.feedback.append((rt.now(), fb))
            )
            server.on_goal(self.goal)

        rt.run_on_hub(send)

    def cancel(self, rt) -> None:
        rt.run_on_hub(self.goal.request_cancel)


@pytest.fixture(scope="module")
def world():
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "open_floor", seed=0, camera=False).start()
    rt.add_subsystem("clients", Clients)
    yield rt, sim
    sim.close()
    rt.close()


@pytest.fixture
def arm(world):
    """The arm back at START, at rest, before each test."""
    rt, sim = world
    rt.call("arm", arm_goal(trajectory((1.5, START)), tolerance=0.01, settle=2.0))
    return rt, sim


def arm_now(sim):
    return sim.robot.arm_positions()


# ------------------------------------------------------------------------------ arm
def test_a_goal_is_followed_and_succeeds_when_its_time_has_come(arm):
    rt, sim = arm
    target = [0.6, -0.4, 0.5, 0.3]
    t0 = rt.now()
    result = rt.call(
        "arm", arm_goal(trajectory((1.0, [0.3, -0.7, 0.4, 0.5]), (2.0, target)), tolerance=0.01, settle=1.0)
    )
    assert result.error_code == R.SUCCESSFUL
    assert rt.now() - t0 >= 2.0  # not before the last point's time
    assert rt.now() - t0 < 3.0
    assert max(abs(a - b) for a, b in zip(arm_now(sim), target)) < 0.01


def test_feedback_tells_desired_actual_and_error_at_the_monitor_rate(arm):
    rt, sim = arm
    probe = Probe(rt, sim.topics.arm.server, arm_goal(trajectory((1.0, [0.3, -0.8, 0.3, 0.7]))))
    rt.call("sleep", 1.5)
    assert probe.status == STATUS_SUCCEEDED and probe.result.error_code == R.SUCCESSFUL
    times = [t for t, _ in probe.feedback]
    assert 15 <= len(times) <= 25  # 20 Hz for ~1 s
    t, fb = probe.feedback[len(probe.feedback) // 2]
    assert list(fb.joint_names) == ARM
    err = [d - a for d, a in zip(fb.desired.positions, fb.actual.positions)]
    assert list(fb.error.positions) == pytest.approx(err)
    assert fb.desired.velocities[0] > 0.1  # joint1 is on its way
    assert fb.header.stamp.sec + fb.header.stamp.nanosec * 1e-9 == pytest.approx(t, abs=0.02)


@pytest.mark.parametrize(
    "traj, code, words",
    [
        (trajectory((1.0, [0.1, 0, 0, 0]), names=["joint1", "joint2", "joint3", "wrist"]), R.INVALID_JOINTS, "'wrist'"),
        (trajectory((1.0, [0.1, 0.2])), R.INVALID_GOAL, "2 positions for 4 joints"),
        (trajectory((1.0, [0.1, 0.2]), names=["joint1", "joint2"]), R.INVALID_JOINTS, "leaves out"),
        (trajectory(names=ARM), R.INVALID_GOAL, "no points"),
        (trajectory((1.0, START), (1.0, START)), R.INVALID_GOAL, "does not increase"),
        (trajectory((1.0, START, [0.1, 0, 0, 0])), R.INVALID_GOAL, "velocity of the last"),
    ],
)
def test_an_invalid_goal_is_aborted_with_the_controllers_error_code(arm, traj, code, words):
    rt, sim = arm
    before = arm_now(sim)
    with pytest.raises(ActorError) as failed:
        rt.call("arm", arm_goal(traj))
    error = failed.value.__cause__
    assert isinstance(error, ActionGoalError) and error.status == STATUS_ABORTED
    assert error.result.error_code == code
    assert words in error.result.error_string
    assert max(abs(a - b) for a, b in zip(arm_now(sim), before)) < 0.01  # nothing moved


def test_an_old_header_stamp_is_refused(arm):
    rt, _ = arm
    traj = trajectory((0.5, START))
    traj.header.stamp = Time(sec=0, nanosec=1)  # long ago, past its 0.5 s
    with pytest.raises(ActorError) as failed:
        rt.call("arm", arm_goal(traj))
    assert failed.value.__cause__.result.error_code == R.OLD_HEADER_TIMESTAMP


def test_an_unreachable_goal_violates_the_goal_tolerance(arm):
    rt, _ = arm
    beyond = [3.5, -1.0, 0.3, 0.7]  # joint1 stops at its limit (pi)
    t0 = rt.now()
    with pytest.raises(ActorError) as failed:
        rt.call("arm", arm_goal(trajectory((1.5, beyond)), tolerance=0.02, settle=0.5))
    result = failed.value.__cause__.result
    assert result.error_code == R.GOAL_TOLERANCE_VIOLATED
    assert "joint1" in result.error_string and "goal_time_tolerance" in result.error_string
    assert rt.now() - t0 == pytest.approx(2.0, abs=0.1)


def test_cancel_brings_the_arm_to_rest_smoothly_and_ends_canceled(arm):
    rt, sim = arm
    probe = Probe(rt, sim.topics.arm.server, arm_goal(trajectory((3.0, [1.8, -0.2, 0.0, 0.2]))))
    rt.call("sleep", 1.0)
    speed = lambda: max(abs(v) for v in sim.robot.joint_states()[1][2:6])  # noqa: E731
    moving = speed()
    assert moving > 0.3
    probe.cancel(rt)
    assert probe.status == STATUS_CANCELED
    speeds = []
    for _ in range(20):
        rt.call("sleep", 0.05)
        speeds.append(speed())
    assert speeds[0] > 0.5 * moving, "decelerates, does not freeze"
    assert speeds[-1] < 0.02, f"still moving at {speeds[-1]:.3f} rad/s 1 s after the cancel"
    assert all(b < a + 0.05 for a, b in zip(speeds, speeds[1:])), speeds
    assert sim.topics.arm.active is None


def test_cancelling_the_client_call_cancels_the_goal(arm):
    rt, sim = arm

    def begin():
        txn = rt.start("arm", arm_goal(trajectory((3.0, [1.8, -0.2, 0.0, 0.2]))))
        rt.call_later(1.0, txn.cancel, "operator stop")
        return txn

    txn = rt.run_on_hub(begin)
    rt.call("sleep", 2.5)
    assert txn.state.name == "CANCELLED"
    assert sim.topics.arm.active is None
    assert max(abs(v) for v in sim.robot.joint_states()[1][2:6]) < 0.02
    assert arm_now(sim)[0] < 1.5  # stopped well short of 1.8


def test_a_new_goal_preempts_the_running_one(arm):
    rt, sim = arm
    first = Probe(rt, sim.topics.arm.server, arm_goal(trajectory((3.0, [1.5, -1.0, 0.3, 0.7]))))
    rt.call("sleep", 0.5)
    target = [-0.5, -0.8, 0.3, 0.6]
    second = Probe(rt, sim.topics.arm.server, arm_goal(trajectory((1.5, target)), tolerance=0.01))
    assert first.status == STATUS_CANCELED
    assert first.result.error_code == R.INVALID_GOAL and first.result.error_string == PREEMPTED
    rt.call("sleep", 2.5)
    assert second.status == STATUS_SUCCEEDED
    assert max(abs(a - b) for a, b in zip(arm_now(sim), target)) < 0.01


def test_a_trajectory_on_the_topic_preempts_a_goal_too(arm):
    rt, sim = arm
    goal = Probe(rt, sim.topics.arm.server, arm_goal(trajectory((3.0, [1.5, -1.0, 0.3, 0.7]))))
    rt.call("sleep", 0.3)
    assert sim.apply_joint_trajectory(trajectory((1.0, START)))
    assert goal.status == STATUS_CANCELED and goal.result.error_string == PREEMPTED
    assert not sim.apply_joint_trajectory(trajectory((1.0, START), names=["joint1", "joint2", "joint3", "x"]))


# ------------------------------------------------------------------------------ gripper
def test_the_position_scale_maps_monotonically_onto_the_fingers():
    from actors.manipulator import gripper_command_position, gripper_width

    assert gripper_opening(GRIPPER_POSITION_CLOSED) == 0.0
    assert gripper_opening(GRIPPER_POSITION_OPEN) == pytest.approx(0.09)
    positions = [GRIPPER_POSITION_CLOSED + k * 0.001 for k in range(30)]
    openings = [gripper_opening(p) for p in positions]
    assert all(b > a for a, b in zip(openings, openings[1:]))
    for p in positions:
        assert gripper_position(gripper_opening(p)) == pytest.approx(min(p, GRIPPER_POSITION_OPEN))
        # the manipulator actors' calibration is the simulated gripper's
        assert gripper_width(p) == pytest.approx(gripper_opening(p))
        assert gripper_command_position(gripper_opening(p)) == pytest.approx(gripper_position(gripper_opening(p)))
    assert gripper_opening(-0.05) == 0.0 and gripper_opening(0.05) == pytest.approx(0.09)


def _grip(rt, position):
    """Send a GripperCommand goal; (status, result) whether it succeeded or not."""
    try:
        return STATUS_SUCCEEDED, rt.call("grip", command=GripperCommandMsg(position=position))
    except ActorError as e:
        return e.__cause__.status, e.__cause__.result


def _ik(x, z, pitch=0.0):
    """base_footprint (x, z) of end_effector_link -> joints (see test_sim_robot)."""
    l1, a0, l2, l3 = math.hypot(0.024, 0.128), math.atan2(0.024, 0.128), 0.124, 0.126
    xs, zs = -0.035 + 0.012, 0.101 + 0.017 + 0.0595
    wx, wz = x - l3 * math.cos(pitch) - xs, z + l3 * math.sin(pitch) - zs
    d = math.hypot(wx, wz)
    up = math.atan2(wz, wx) + math.acos((l1**2 + d**2 - l2**2) / (2 * l1 * d))
    fore = math.atan2(wz - l1 * math.sin(up), wx - l1 * math.cos(up))
    j2 = (math.pi / 2 - a0) - up
    j3 = -fore - j2
    return [0.0, j2, j3, pitch - j2 - j3]


def test_closing_on_nothing_reaches_the_closed_position(world):
    rt, _ = world
    status, result = _grip(rt, GRIPPER_POSITION_OPEN)
    assert status == STATUS_SUCCEEDED and result.reached_goal
    assert result.position == pytest.approx(GRIPPER_POSITION_OPEN, abs=0.0005)
    status, result = _grip(rt, GRIPPER_POSITION_CLOSED)
    assert status == STATUS_SUCCEEDED
    assert result.reached_goal and not result.stalled
    assert result.position == pytest.approx(GRIPPER_POSITION_CLOSED, abs=0.0005)


def test_closing_on_a_can_stalls_short_of_the_closed_position(world):
    rt, sim = world
    sim.set_object_pose("can_1", 0.26, 0.0)
    assert _grip(rt, GRIPPER_POSITION_OPEN)[0] == STATUS_SUCCEEDED
    rt.call("arm", arm_goal(trajectory((2.0, _ik(0.26, 0.20))), tolerance=0.01, settle=2.0))
    rt.call("arm", arm_goal(trajectory((1.5, _ik(0.26, 0.062))), tolerance=0.01, settle=2.0))
    t0 = rt.now()
    status, result = _grip(rt, GRIPPER_POSITION_CLOSED)
    # the TurtleBot3's gripper controller aborts a stalled goal (allow_stalling false)
    assert status == STATUS_ABORTED
    assert result.stalled and not result.reached_goal
    assert result.position > GRIPPER_POSITION_CLOSED + 0.015  # held open by the can
    assert gripper_opening(result.position) == pytest.approx(0.066, abs=0.004)
    assert result.effort > 0
    assert rt.now() - t0 >= sim.topics.gripper.config.stall_timeout
    assert sim.in_gripper("can_1")
    # opening again lets go and reaches the goal
    status, result = _grip(rt, GRIPPER_POSITION_OPEN)
    assert status == STATUS_SUCCEEDED and result.reached_goal
    rt.call("arm", arm_goal(trajectory((1.5, START)), tolerance=0.01, settle=2.0))
    sim.set_object_pose("can_1", 2.0, 2.0)


def test_a_gripper_goal_preempts_the_last_and_a_cancel_holds(world):
    rt, sim = world
    _grip(rt, GRIPPER_POSITION_CLOSED)
    server = sim.topics.gripper.server
    first = Probe(rt, server, GripperCommand.Goal(command=GripperCommandMsg(position=GRIPPER_POSITION_OPEN)))
    rt.call("sleep", 0.1)
    second = Probe(rt, server, GripperCommand.Goal(command=GripperCommandMsg(position=0.0)))
    assert first.status == STATUS_CANCELED
    rt.call("sleep", 0.05)
    assert second.feedback, "feedback while it moves"
    second.cancel(rt)
    assert second.status == STATUS_CANCELED
    held = sim.robot.gripper_opening()
    rt.call("sleep", 0.5)
    assert sim.robot.gripper_opening() == pytest.approx(held, abs=0.003)  # holds where it was
