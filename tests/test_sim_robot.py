"""The simulated robot through its ROS topics (and its gripper action), under the virtual
clock, on open_floor: driving, turning, arm trajectories, a friction grasp, determinism."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from control_msgs.action import GripperCommand
from control_msgs.msg import GripperCommand as GripperCommandMsg
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bt_engine import Runtime
from planning import ArmKinematics
from sim import SimWorld
from sim.actuators import gripper_position
from sim.topics import CMD_VEL

ARM = ["joint1", "joint2", "joint3", "joint4"]


class Robot:
    """A test's view of the robot: only topics (plus the world's ground truth)."""

    def __init__(self, rt, sim):
        self.rt, self.sim = rt, sim
        self.last = {}
        bus = rt.bus
        self.subs = [
            bus.subscribe("/odom", Odometry, self._keep("odom")),
            bus.subscribe("/ground_truth/pose", PoseStamped, self._keep("gt")),
            bus.subscribe("/joint_states", JointState, self._keep("js")),
        ]
        self.cmd_vel = bus.publisher(CMD_VEL, TwistStamped)
        self.traj = bus.publisher("/arm_controller/joint_trajectory", JointTrajectory)
        self.grip_goal = rt.run_on_hub(
            bus.register_action, rt.root, "_grip", GripperCommand, "/gripper_controller/gripper_cmd"
        )

    def _keep(self, key):
        def cb(msg):
            self.last[key] = msg

        return cb

    def sleep(self, seconds):
        self.rt.call("sleep", seconds)

    def drive(self, v, w, seconds):
        tw = TwistStamped()
        tw.twist.linear.x, tw.twist.angular.z = float(v), float(w)
        period = 0.1  # as a controller does: diff_drive_controller brakes after 0.5 s without
        for _ in range(round(seconds / period)):
            self.cmd_vel.publish(tw)
            self.sleep(period)
        self.cmd_vel.publish(TwistStamped())
        self.sleep(1.0)

    def move_arm(self, q, seconds):
        msg = JointTrajectory()
        msg.joint_names = ARM
        pt = JointTrajectoryPoint()
        pt.positions = [float(x) for x in q]
        pt.time_from_start = _dur(seconds)
        msg.points = [pt]
        self.traj.publish(msg)
        self.sleep(seconds + 0.3)

    def grip(self, width, seconds=1.0):
        """Send the gripper to a finger opening [m] and wait ``seconds`` (the goal may end
        stalled on an object: aborted, which is fine here)."""
        goal = GripperCommand.Goal(command=GripperCommandMsg(position=gripper_position(width)))
        self.rt.run_on_hub(lambda: self.rt.start("_grip", goal, on_done=lambda r: None))
        self.sleep(seconds)

    def odom(self):
        o = self.last["odom"].pose.pose
        return o.position.x, o.position.y, 2 * math.atan2(o.orientation.z, o.orientation.w)

    def ground_truth(self):
        g = self.last["gt"].pose
        return g.position.x, g.position.y, 2 * math.atan2(g.orientation.z, g.orientation.w)

    def arm(self):
        js = self.last["js"]
        return [js.position[list(js.name).index(n)] for n in ARM]


def _dur(t):
    return Duration(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))


@pytest.fixture
def robot():
    rt = Runtime(clock="virtual")
    # the test reads the exact pose from the bus: ask for it whatever the default
    sim = SimWorld(rt, "open_floor", seed=0, camera=False, debug_ground_truth=True).start()
    r = Robot(rt, sim)
    r.sleep(0.2)
    yield r
    sim.close()
    rt.close()


def test_drive_one_metre(robot):
    robot.drive(0.2, 0.0, 5.0)
    ox, oy, _ = robot.odom()
    gx, gy, _ = robot.ground_truth()
    assert math.hypot(ox - 1.0, oy) < 0.03, (ox, oy)
    assert math.hypot(gx - 1.0, gy) < 0.03, (gx, gy)
    assert robot.sim.robot_pose()[0] == pytest.approx(gx)


def test_turn_ninety_degrees(robot):
    robot.drive(0.0, 0.5, (math.pi / 2) / 0.5)
    assert abs(math.degrees(robot.ground_truth()[2]) - 90) < 3
    assert abs(math.degrees(robot.odom()[2]) - 90) < 3


def test_speed_is_clamped_to_turtlebot3_limits(robot):
    robot.drive(1.0, 0.0, 2.0)  # asks 1 m/s; the Waffle Pi does 0.26 m/s
    assert robot.ground_truth()[0] == pytest.approx(0.26 * 2.0, abs=0.05)


def test_joint_trajectory_is_tracked(robot):
    msg = JointTrajectory()
    msg.joint_names = ARM
    goals = [[0.3, -0.5, 0.4, 0.6], [0.8, 0.2, 0.1, 0.9], [-0.6, 0.4, 0.3, -0.5]]
    for i, q in enumerate(goals):
        pt = JointTrajectoryPoint()
        pt.positions = q
        pt.time_from_start = _dur(1.5 * (i + 1))
        msg.points.append(pt)
    robot.traj.publish(msg)
    robot.sleep(1.5)
    assert np.max(np.abs(np.subtract(robot.arm(), goals[0]))) < 0.05  # on its way
    robot.sleep(3.3)
    err = np.abs(np.subtract(robot.arm(), goals[-1]))
    assert np.max(err) < 0.02, err


def _ik(x, z, pitch=0.0):
    """OpenManipulator-X on the Waffle Pi: base_footprint (x, z) of end_effector_link -> joints.
    Elbow up; pitch 0 = gripper horizontal. Dimensions from the URDF."""
    l1, a0, l2, l3 = math.hypot(0.024, 0.128), math.atan2(0.024, 0.128), 0.124, 0.126
    xs, zs = -0.035 + 0.012, 0.101 + 0.017 + 0.0595
    wx, wz = x - l3 * math.cos(pitch) - xs, z + l3 * math.sin(pitch) - zs
    d = math.hypot(wx, wz)
    up = math.atan2(wz, wx) + math.acos((l1**2 + d**2 - l2**2) / (2 * l1 * d))
    fore = math.atan2(wz - l1 * math.sin(up), wx - l1 * math.cos(up))
    j2 = (math.pi / 2 - a0) - up
    j3 = -fore - j2
    return [0.0, j2, j3, pitch - j2 - j3]


def test_friction_grasp_holds_a_can(robot):
    sim = robot.sim
    sim.set_object_pose("can_1", 0.26, 0.0)
    robot.grip(0.09, 0.5)
    robot.move_arm(_ik(0.26, 0.20), 2.0)  # above the can, fingers open
    robot.move_arm(_ik(0.26, 0.062), 1.5)  # straddle it
    robot.grip(0.0, 1.5)  # squeeze
    opening = sum(robot.last["js"].position[-2:])
    assert opening == pytest.approx(0.066, abs=0.004)  # stopped by the can
    z0 = sim.object_pose("can_1")[2]
    robot.move_arm(_ik(0.26, 0.162), 1.5)  # lift 10 cm
    z1 = sim.object_pose("can_1")[2]
    assert z1 - z0 == pytest.approx(0.10, abs=0.01)
    robot.sleep(2.0)
    z2 = sim.object_pose("can_1")[2]
    assert sim.in_gripper("can_1")
    assert abs(z2 - z1) < 0.005, (z1, z2)
    assert _constraints_on(sim, sim.scene.objects["can_1"]) == []  # friction only


def _constraints_on(sim, body):
    cid = sim.cid
    infos = [
        p.getConstraintInfo(p.getConstraintUniqueId(i, physicsClientId=cid), physicsClientId=cid)
        for i in range(p.getNumConstraints(physicsClientId=cid))
    ]
    return [info for info in infos if body in (info[0], info[2])]


def test_the_fingers_move_as_one_and_a_held_can_does_not_slide_between_them():
    """One servo drives both fingers through a linkage (the right finger mimics the left in
    ROBOTIS' URDF): pushed sideways, a held can takes both fingers with it or neither."""
    sim = SimWorld(None, "open_floor", seed=0, camera=False, cmd_vel_timeout=0)
    try:
        kin, reach = ArmKinematics.from_urdf(), 0.26
        sim.robot.set_gripper(0.09)
        sim.robot.set_arm(kin.ik(reach, 0.0, 0.062, 0.0).best)
        sim.advance(2.0)
        ee = sim.link_pose("end_effector_link")[0]
        sim.set_object_pose("can_1", ee[0], ee[1])
        sim.robot.set_gripper(0.0)
        sim.advance(1.5)
        sim.set_arm_positions(kin.ik(reach, 0.0, 0.162, 0.0).best, 1.5)
        sim.advance(2.0)
        can = sim.scene.objects["can_1"]

        def fingers():
            return [s[0] for s in p.getJointStates(sim.robot.body, sim.robot.grip_idx, physicsClientId=sim.cid)]

        left, right = fingers()
        assert left == pytest.approx(right, abs=0.0005)
        for _ in range(round(1.0 / sim.dt)):  # 3 N sideways for a second, about its weight
            p.applyExternalForce(can, -1, [0.0, 3.0, 0.0], [0, 0, 0], p.LINK_FRAME, physicsClientId=sim.cid)
            sim.step()
        left, right = fingers()
        assert left == pytest.approx(right, abs=0.001)
        assert sim.in_gripper("can_1")
    finally:
        sim.close()


def _scripted_run(seed):
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "open_floor", seed=seed, camera=False, cmd_vel_timeout=0).start()
    try:
        r = Robot(rt, sim)
        tw = TwistStamped()
        tw.twist.linear.x, tw.twist.angular.z = 0.15, 0.3
        r.cmd_vel.publish(tw)
        msg = JointTrajectory()
        msg.joint_names = ARM
        pt = JointTrajectoryPoint()
        pt.positions = [0.4, 0.3, 0.2, 0.1]
        pt.time_from_start = _dur(1.0)
        msg.points = [pt]
        r.traj.publish(msg)
        r.sleep(3.0)
        return sim.spec.objects, sim.state_vector(), sim.ticks
    finally:
        sim.close()
        rt.close()


def test_same_seed_same_state_after_n_steps():
    objs_a, state_a, ticks_a = _scripted_run(4)
    objs_b, state_b, ticks_b = _scripted_run(4)
    assert objs_a == objs_b
    assert ticks_a == ticks_b == 180
    assert np.array_equal(state_a, state_b)
    objs_c, state_c, _ = _scripted_run(5)
    assert objs_c != objs_a


def test_odometry_noise_model_is_configurable():
    from sim.sensors import OdomNoise

    ends = {}
    for name, noise in (("exact", OdomNoise.exact()), ("biased", OdomNoise.exact(radius_bias=0.05))):
        sim = SimWorld(None, "open_floor", seed=0, camera=False, odom_noise=noise, cmd_vel_timeout=0)
        try:
            sim.apply_cmd_vel(0.2, 0.0)
            sim.advance(5.0)
            sim.apply_cmd_vel(0.0, 0.0)
            sim.advance(1.0)
            ends[name] = (sim.odom_pose()[0], sim.robot_pose()[0])
        finally:
            sim.close()
    odom, truth = ends["exact"]
    assert odom == pytest.approx(truth, abs=0.005)
    odom, truth = ends["biased"]
    assert odom == pytest.approx(1.05 * truth, abs=0.005)  # 5 % long wheel radius


def test_wall_clock_runs_in_real_time():
    import time

    with Runtime(clock="wall") as rt:
        sim = SimWorld(rt, "open_floor", seed=0, camera=False).start()
        try:
            t0 = time.perf_counter()
            rt.call("sleep", 0.5)
            wall = time.perf_counter() - t0
            assert sim.now() == pytest.approx(rt.now(), abs=0.05)
            assert sim.ticks == pytest.approx(60 * wall, abs=6)
        finally:
            sim.close()
