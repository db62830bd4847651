"""The real robot's ROS 2 Jazzy interface types that have no pip wheel, built at install from
interfaces/upstream: tf2_msgs/TFMessage, control_msgs FollowJointTrajectory and GripperCommand,
nav2_msgs NavigateToPose. They must match upstream Jazzy exactly, so that they interoperate
with a real robot: fields and constants as upstream, and the RIHS01 type hashes that Jazzy
computes from the definitions (and checks on the wire) equal to those of upstream's builds.
Then real rclpy over Fast DDS on loopback: a TFMessage topic, and a goal with feedback and a
result for each action."""

from __future__ import annotations

import ctypes
import os
import sys
import threading
import time
from pathlib import Path

import pytest

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
from action_msgs.msg import GoalStatus  # noqa: E402
from builtin_interfaces.msg import Duration  # noqa: E402
from control_msgs.action import FollowJointTrajectory, GripperCommand  # noqa: E402
from control_msgs.msg import GripperCommand as GripperCommandMsg  # noqa: E402
from control_msgs.msg import JointComponentTolerance, JointTolerance  # noqa: E402
from geometry_msgs.msg import TransformStamped  # noqa: E402
from nav2_msgs.action import NavigateToPose  # noqa: E402
from rclpy.action import ActionClient, ActionServer  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.executors import MultiThreadedExecutor  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from trajectory_msgs.msg import JointTrajectoryPoint  # noqa: E402

UPSTREAM = Path(__file__).resolve().parents[1] / "interfaces" / "upstream"

# Fields as in upstream Jazzy: tf2_msgs (geometry2 0.36.x), control_msgs 5.x, nav2_msgs
# (navigation2 1.3.x). Types as rosidl's Python classes name them.
FIELDS = {
    TFMessage: {"transforms": "sequence<geometry_msgs/TransformStamped>"},
    JointTolerance: {"name": "string", "position": "double", "velocity": "double", "acceleration": "double"},
    JointComponentTolerance: {
        "joint_name": "string",
        "component": "uint16",
        "position": "double",
        "velocity": "double",
        "acceleration": "double",
    },
    GripperCommandMsg: {"position": "double", "max_effort": "double"},
    FollowJointTrajectory.Goal: {
        "trajectory": "trajectory_msgs/JointTrajectory",
        "multi_dof_trajectory": "trajectory_msgs/MultiDOFJointTrajectory",
        "path_tolerance": "sequence<control_msgs/JointTolerance>",
        "component_path_tolerance": "sequence<control_msgs/JointComponentTolerance>",
        "goal_tolerance": "sequence<control_msgs/JointTolerance>",
        "component_goal_tolerance": "sequence<control_msgs/JointComponentTolerance>",
        "goal_time_tolerance": "builtin_interfaces/Duration",
    },
    FollowJointTrajectory.Result: {"error_code": "int32", "error_string": "string"},
    FollowJointTrajectory.Feedback: {
        "header": "std_msgs/Header",
        "joint_names": "sequence<string>",
        "desired": "trajectory_msgs/JointTrajectoryPoint",
        "actual": "trajectory_msgs/JointTrajectoryPoint",
        "error": "trajectory_msgs/JointTrajectoryPoint",
        "multi_dof_joint_names": "sequence<string>",
        "multi_dof_desired": "trajectory_msgs/MultiDOFJointTrajectoryPoint",
        "multi_dof_actual": "trajectory_msgs/MultiDOFJointTrajectoryPoint",
        "multi_dof_error": "trajectory_msgs/MultiDOFJointTrajectoryPoint",
    },
    GripperCommand.Goal: {"command": "control_msgs/GripperCommand"},
    GripperCommand.Result: {"position": "double", "effort": "double", "stalled": "boolean", "reached_goal": "boolean"},
    GripperCommand.Feedback: {
        "position": "double",
        "effort": "double",
        "stalled": "boolean",
        "reached_goal": "boolean",
    },
    NavigateToPose.Goal: {"pose": "geometry_msgs/PoseStamped", "behavior_tree": "string"},
    NavigateToPose.Result: {"error_code": "uint16", "error_msg": "string"},
    NavigateToPose.Feedback: {
        "current_pose": "geometry_msgs/PoseStamped",
        "navigation_time": "builtin_interfaces/Duration",
        "estimated_time_remaining": "builtin_interfaces/Duration",
        "number_of_recoveries": "int16",
        "distance_remaining": "float",
    },
}

# Constants are not part of the type hash, so they are checked here one by one.
CONSTANTS = {
    JointComponentTolerance: {"X_AXIS": 1, "Y_AXIS": 2, "Z_AXIS": 3, "TRANSLATION": 4, "ROTATION": 5},
    FollowJointTrajectory.Result: {
        "SUCCESSFUL": 0,
        "INVALID_GOAL": -1,
        "INVALID_JOINTS": -2,
        "OLD_HEADER_TIMESTAMP": -3,
        "PATH_TOLERANCE_VIOLATED": -4,
        "GOAL_TOLERANCE_VIOLATED": -5,
    },
    NavigateToPose.Result: {"NONE": 0},  # Jazzy's only error code
}

# RIHS01 type hashes of upstream's Jazzy builds (the same values appear in rosidl output
# generated from upstream's own files, and TFMessage's in rmw_zenoh's key expressions).
# A type's hash covers the full description of every type it references, so e.g. the Goal's
# also pins JointTolerance and JointComponentTolerance.
HASHES = {
    "tf2_msgs/msg/TFMessage": "e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "control_msgs/msg/JointTolerance": "c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
    "control_msgs/msg/JointComponentTolerance": "739ea7566931944d33830fa10f1bf5e7a7fbdc3172bce7a7eaac642bd6e3ffa4",
    "control_msgs/msg/GripperCommand": "57eb8f326c9889ca8bb34ead82cc94cc09bf6bc5c3b6c09546dca3a00b589890",
    "control_msgs/action/FollowJointTrajectory": "738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
    "control_msgs/action/FollowJointTrajectory_Goal": "8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
    "control_msgs/action/FollowJointTrajectory_Result": "8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
    "control_msgs/action/FollowJointTrajectory_Feedback": "3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49",
    "control_msgs/action/FollowJointTrajectory_SendGoal": "b13789dddc325a7a962825c45e28c77d37237ec129dd0c34dc5994562938c57f",
    "control_msgs/action/FollowJointTrajectory_GetResult": "e3ceb38e3e1867c8dc0f46014df26e90eb93422f27e9e97f936e07f94be4bc8b",
    "control_msgs/action/FollowJointTrajectory_FeedbackMessage": "80398fcb9674a79081a9906e2ccf0c804dd7cb15e22e362e606ee87186beab71",
    "control_msgs/action/GripperCommand": "e17c0e644eccf14bea84a0a93e0977182872c2eb7873ca6694900059b46dbc84",
    "control_msgs/action/GripperCommand_Goal": "607d9f41eb241e1922e90f02125e87ae6bfb78f7f64a71dc92630263d01f8b6d",
    "control_msgs/action/GripperCommand_Result": "bf512d5aa6a0e4fe4d8be22b2ec4a1973c3d250fa1f65e47450322c25c45c0a0",
    "control_msgs/action/GripperCommand_Feedback": "8f7c520077bab528bb9161ee3b83c81eee1f8aecadb8922ce82c79d667a819c4",
    "control_msgs/action/GripperCommand_SendGoal": "6bf8cc4ce80cd499e7dd3258c03c50c3fa6672b469ff8355339ef1df77fcd212",
    "control_msgs/action/GripperCommand_GetResult": "7e60a7606063d4a2728d21badac099e68b734a196ac3ab42d1d4c668eb0bb3cd",
    "control_msgs/action/GripperCommand_FeedbackMessage": "392ff03fcd872f9dc2405cbeb2897fcf011ad9998458b6aa85c603b8a49e431d",
    "nav2_msgs/action/NavigateToPose": "a56dba8a3234a1215e610180dc703ae25bbf406dded8b54887891c9732857eab",
    "nav2_msgs/action/NavigateToPose_Goal": "22a9dffbd6733011220460bd52edbc7843c8fc86282d40bc7ad3ca176a9dec10",
    "nav2_msgs/action/NavigateToPose_Result": "ddbff7fc6d1e51d774d5defdb8398a57cb23fa8709355002d676408bb4860b85",
    "nav2_msgs/action/NavigateToPose_Feedback": "9ebc544c7d41bd8c6060b191bf9f5e4ddca6c2f61ee9e04fcb62ed5d67218a33",
    "nav2_msgs/action/NavigateToPose_SendGoal": "a4fcb3bee1bf32e21a0e541a943b221aa0826996e2c98f079b47022b256f48b5",
    "nav2_msgs/action/NavigateToPose_GetResult": "c407920357d566771e8882b4ef4d1f1a84ee922d609920ccd57faa6d6e391dc5",
    "nav2_msgs/action/NavigateToPose_FeedbackMessage": "9d1f6fa2eb975ce733b419ac2e97b134d8ff92b6478b6559feed9a50bdfd82b3",
}


class _TypeHash(ctypes.Structure):  # rosidl_type_hash_t
    _fields_ = [("version", ctypes.c_uint8), ("value", ctypes.c_uint8 * 32)]


def compiled_type_hash(type_name: str) -> str:
    """The hash compiled into the package's C library, as rmw uses it on the wire."""
    pkg = type_name.split("/")[0]
    lib = ctypes.CDLL(f"lib{pkg}__rosidl_generator_c.so")  # found via the venv's library path
    fn = getattr(lib, type_name.replace("/", "__") + "__get_type_hash")
    fn.restype = ctypes.POINTER(_TypeHash)
    fn.argtypes = [ctypes.c_void_p]  # the type support argument is unused
    h = fn(None).contents
    return f"RIHS{h.version:02}_{bytes(h.value).hex()}"


@pytest.mark.parametrize("cls", list(FIELDS), ids=lambda c: c.__name__)
def test_fields_and_constants_are_upstream_jazzy(cls):
    assert cls.get_fields_and_field_types() == FIELDS[cls]
    constants = getattr(type(cls), f"_Metaclass_{cls.__name__}__constants")
    assert constants == CONSTANTS.get(cls, {})
    for name, value in constants.items():
        assert getattr(cls, name) == value


@pytest.mark.parametrize("type_name", list(HASHES))
def test_type_hashes_equal_upstream_builds(type_name):
    assert compiled_type_hash(type_name) == "RIHS01_" + HASHES[type_name]


def test_the_installed_definitions_are_the_ones_in_the_repository():
    """A definition changed in interfaces/upstream but not rebuilt shows here (make venv)."""
    sources = sorted(p for p in UPSTREAM.glob("*/*/*") if p.suffix in (".msg", ".srv", ".action"))
    assert {p.parent.parent.name for p in sources} == {"tf2_msgs", "control_msgs", "nav2_msgs"}
    for src in sources:
        pkg = src.parent.parent.name
        installed = Path(sys.prefix) / "share" / pkg / src.parent.name / src.name  # venv root
        assert installed.read_text() == src.read_text(), f"{pkg}/{src.parent.name}/{src.name}"


# ---------------------------------------------------------------------------------------
# Over real DDS on loopback

PREFIX = f"/actorbt_ifc_test_{os.getpid()}"


def wait_for(pred, timeout=10.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.02)
    return pred()


def wait_future(fut, timeout=10.0):
    done = threading.Event()
    fut.add_done_callback(lambda _f: done.set())
    assert done.wait(timeout), "timed out"
    return fut.result()


@pytest.fixture(scope="module")
def nodes():
    """A server node and a client node in their own rclpy context, spun in a thread."""
    ctx = Context()
    rclpy.init(context=ctx)
    server = rclpy.create_node(f"ifc_server_{os.getpid()}", context=ctx)
    client = rclpy.create_node(f"ifc_client_{os.getpid()}", context=ctx)
    executor = MultiThreadedExecutor(num_threads=4, context=ctx)
    executor.add_node(server)
    executor.add_node(client)
    spinner = threading.Thread(target=executor.spin, name="ifc-spin", daemon=True)
    spinner.start()
    try:
        yield server, client
    finally:
        executor.shutdown()
        spinner.join(5)
        server.destroy_node()
        client.destroy_node()
        rclpy.shutdown(context=ctx)


def publisher_type_hash(node, topic):
    infos = node.get_publishers_info_by_topic(topic)
    assert len(infos) == 1, infos
    return infos[0].topic_type, str(infos[0].topic_type_hash)


def test_tf_message_over_dds(nodes):
    server, client = nodes
    topic = f"{PREFIX}/tf"
    got = []
    sub = client.create_subscription(TFMessage, topic, got.append, 10)
    pub = server.create_publisher(TFMessage, topic, 10)
    try:
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = "odom", "base_footprint"
        t.transform.translation.x = 1.5
        t.transform.rotation.w = 1.0
        assert wait_for(lambda: pub.get_subscription_count() == 1)
        assert wait_for(lambda: (pub.publish(TFMessage(transforms=[t])), bool(got))[1])
        tf = got[0].transforms[0]
        assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_footprint")
        assert tf.transform.translation.x == 1.5 and tf.transform.rotation.w == 1.0
        assert publisher_type_hash(client, topic) == (
            "tf2_msgs/msg/TFMessage",
            "RIHS01_" + HASHES["tf2_msgs/msg/TFMessage"],
        )
    finally:
        server.destroy_publisher(pub)
        client.destroy_subscription(sub)


def _fjt_goal():
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = ["joint1", "joint2", "joint3", "joint4"]
    goal.trajectory.points = [JointTrajectoryPoint(positions=[0.0, -1.0, 0.3, 0.7], time_from_start=Duration(sec=2))]
    goal.goal_tolerance = [JointTolerance(name="joint1", position=0.01)]
    goal.component_path_tolerance = [
        JointComponentTolerance(joint_name="base", component=JointComponentTolerance.TRANSLATION, position=0.1)
    ]
    goal.goal_time_tolerance = Duration(sec=1)
    return goal


def _fjt_feedback(goal, i):
    fb = FollowJointTrajectory.Feedback(joint_names=list(goal.trajectory.joint_names))
    fb.actual.positions = [0.1 * i] * 4
    return fb


def _fjt_result(goal):
    return FollowJointTrajectory.Result(
        error_code=FollowJointTrajectory.Result.SUCCESSFUL, error_string=f"{len(goal.trajectory.points)} point(s)"
    )


def _gripper_goal():
    return GripperCommand.Goal(command=GripperCommandMsg(position=0.019, max_effort=5.0))


def _gripper_feedback(goal, i):
    return GripperCommand.Feedback(position=goal.command.position * i / 2, effort=1.0)


def _gripper_result(goal):
    return GripperCommand.Result(position=goal.command.position, effort=2.0, stalled=True, reached_goal=False)


def _nav_goal():
    goal = NavigateToPose.Goal(behavior_tree="")
    goal.pose.header.frame_id = "map"
    goal.pose.pose.position.x, goal.pose.pose.position.y = 2.0, -1.0
    goal.pose.pose.orientation.w = 1.0
    return goal


def _nav_feedback(goal, i):
    fb = NavigateToPose.Feedback(number_of_recoveries=i, distance_remaining=3.0 - i)
    fb.navigation_time.sec = i
    return fb


def _nav_result(goal):
    return NavigateToPose.Result(error_code=NavigateToPose.Result.NONE, error_msg=goal.pose.header.frame_id)


ACTIONS = {
    "follow_joint_trajectory": (
        FollowJointTrajectory,
        _fjt_goal,
        _fjt_feedback,
        _fjt_result,
        "control_msgs/action/FollowJointTrajectory",
    ),
    "gripper_cmd": (
        GripperCommand,
        _gripper_goal,
        _gripper_feedback,
        _gripper_result,
        "control_msgs/action/GripperCommand",
    ),
    "navigate_to_pose": (NavigateToPose, _nav_goal, _nav_feedback, _nav_result, "nav2_msgs/action/NavigateToPose"),
}


@pytest.mark.parametrize("name", list(ACTIONS))
def test_action_goal_feedback_and_result_over_dds(nodes, name):
    server_node, client_node = nodes
    action_type, make_goal, make_feedback, make_result, type_name = ACTIONS[name]
    action_name = f"{PREFIX}/{name}"
    seen_goals = []

    def execute(goal_handle):
        seen_goals.append(goal_handle.request)
        for i in range(3):
            goal_handle.publish_feedback(make_feedback(goal_handle.request, i))
            time.sleep(0.05)
        goal_handle.succeed()
        return make_result(goal_handle.request)

    server = ActionServer(server_node, action_type, action_name, execute)
    client = ActionClient(client_node, action_type, action_name)
    try:
        assert client.wait_for_server(timeout_sec=10)
        goal = make_goal()
        feedback = []
        handle = wait_future(client.send_goal_async(goal, feedback_callback=lambda msg: feedback.append(msg.feedback)))
        assert handle is not None and handle.accepted
        response = wait_future(handle.get_result_async())
        assert response.status == GoalStatus.STATUS_SUCCEEDED
        assert seen_goals == [goal]  # the goal crossed the wire intact
        assert response.result == make_result(goal)
        assert wait_for(lambda: len(feedback) == 3)
        assert feedback == [make_feedback(goal, i) for i in range(3)]
        # The feedback topic carries upstream's hash for the type.
        assert publisher_type_hash(client_node, f"{action_name}/_action/feedback") == (
            f"{type_name}_FeedbackMessage",
            "RIHS01_" + HASHES[f"{type_name}_FeedbackMessage"],
        )
    finally:
        client.destroy()
        server.destroy()
