"""`actorbt topic list | echo | hz` (issue [senses]) and `actorbt action list` beside it
(bt_cli/action.py): on the local bus in this process, where the virtual clock runs
the simulated world fast and times are sim time, and over ROS against an `actorbt sim run
--bus ros` in another process. Also what they stand on: the bus's topic listing and the
message converter."""

from __future__ import annotations

import array
import json
import os
import select
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest
import yaml

from bt_engine import Runtime
from bt_engine.bus.messages import UnknownTypeError, message_class, to_plain, type_name
from bt_cli.main import main
from bt_cli.topic import Rate, format_yaml, unknown_topic_message

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def world_config(tmp_path_factory):
    """An actorbt.yaml with the house world alone (no subsystems: quick to start)."""
    folder = tmp_path_factory.mktemp("topic")
    cfg = folder / "actorbt.yaml"
    cfg.write_text(
        textwrap.dedent("""\
        subsystems: {}
        trees: null
        world: {name: house, seed: 0}
        simulator: sim:start_world
        transport: local
        clock: virtual
        plugins: [sim.cli]
        """)
    )
    return str(cfg)


def run(capsys, cfg, *argv):
    rc = main(["--config", cfg, "topic", *argv])
    out, err = capsys.readouterr()
    return rc, out, err


# -- the pieces ------------------------------------------------------------------------------
def test_type_names_and_classes():
    from control_msgs.action import FollowJointTrajectory
    from sensor_msgs.msg import LaserScan

    assert type_name(LaserScan) == "sensor_msgs/msg/LaserScan"
    assert type_name(FollowJointTrajectory) == "control_msgs/action/FollowJointTrajectory"
    for name in ("sensor_msgs/msg/LaserScan", "sensor_msgs/LaserScan", "sensor_msgs.msg.LaserScan"):
        assert message_class(name) is LaserScan
    with pytest.raises(UnknownTypeError):
        message_class("no_such_msgs/msg/Thing")


def test_messages_become_plain_data_with_ros_field_names():
    from sensor_msgs.msg import CameraInfo, Image, LaserScan

    scan = LaserScan(range_max=3.5, angle_increment=0.017453292519943295)
    scan.header.frame_id = "base_scan"
    scan.ranges = array.array("f", [0.1, float("inf"), float("nan")] + [1.0] * 300)
    plain = to_plain(scan)
    assert list(plain) == list(LaserScan.get_fields_and_field_types())
    assert plain["header"] == {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "base_scan"}
    assert plain["angle_increment"] == 0.017453293  # float32 shown as float32
    assert plain["ranges"][0] == 0.1 and plain["ranges"][1] == float("inf")
    assert len(plain["ranges"]) == 129 and plain["ranges"][-1] == "..."  # ros2's 128, then '...'
    assert to_plain(scan, finite=True)["ranges"][1:3] == [None, None]  # for JSON
    assert len(to_plain(scan, truncate=None)["ranges"]) == 303
    image = Image(height=2, width=2, encoding="rgb8", step=6, data=array.array("B", range(12)))
    assert to_plain(image, arrays=False)["data"] == "<sequence<uint8>, length: 12>"
    info = to_plain(CameraInfo(k=np.arange(9, dtype=float)))  # a numpy array field
    assert info["k"] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]
    json.dumps(to_plain(scan, finite=True), allow_nan=False)


def test_no_arr_leaves_out_arrays_of_numbers_but_not_of_messages_or_strings():
    from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
    from sensor_msgs.msg import JointState
    from tf2_msgs.msg import TFMessage

    arm = TransformStamped(child_frame_id="link1")
    arm.header.frame_id = "base_link"
    plain = to_plain(TFMessage(transforms=[arm, TransformStamped()]), arrays=False)
    assert [t["child_frame_id"] for t in plain["transforms"]] == ["link1", ""]
    assert plain["transforms"][0]["header"]["frame_id"] == "base_link"
    joints = to_plain(JointState(name=["joint1", "joint2"], position=[0.1, 0.2]), arrays=False)
    assert joints["name"] == ["joint1", "joint2"]
    assert joints["position"] == "<sequence<double>, length: 2>"
    pose = to_plain(PoseWithCovarianceStamped(), arrays=False)  # a fixed-size array too
    assert pose["pose"]["covariance"] == "<double[36], length: 36>"


def test_yaml_prints_fields_on_lines_and_number_lists_on_one():
    from geometry_msgs.msg import PoseStamped

    text = format_yaml({"pose": to_plain(PoseStamped())["pose"], "k": [1.0, 2.0]})
    assert "  position:\n    x: 0.0\n" in text and "k: [1.0, 2.0]\n" in text


def test_the_rate_is_ros2s():
    rate = Rate.of([0.0, 0.2, 0.4, 0.7])
    assert rate.window == 4 and rate.min == pytest.approx(0.2) and rate.max == pytest.approx(0.3)
    assert rate.rate == pytest.approx(3 / 0.7)
    assert rate.text("sim time").splitlines()[0] == "average rate: 4.286 (sim time)"
    assert Rate.of([1.0]) is None


def test_close_matches_of_an_unknown_topic():
    names = ["/scan", "/odom", "/camera/color/image_raw", "/camera/depth/image_raw"]
    assert unknown_topic_message("/scna", names) == "unknown topic /scna; did you mean /scan?"
    assert "/camera/color/image_raw" in unknown_topic_message("/image_raw", names)
    assert "`actorbt topic list`" in unknown_topic_message("/zzz", names)


def test_the_local_bus_lists_its_topics_and_actions():
    from control_msgs.action import GripperCommand
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan

    with Runtime() as rt:

        def setup():
            bus = rt.bus
            bus.publisher("/scan", LaserScan, "sensor")
            bus.subscribe("/scan", LaserScan, lambda m: None)
            bus.subscribe("/cmd_vel", Twist, lambda m: None)
            bus.action_server("/gripper_controller/gripper_cmd", GripperCommand, lambda g: None)
            return bus.topics(), bus.actions(), bus.services()

        topics, actions, services = rt.run_on_hub(setup)
    assert [tuple(t) for t in topics] == [
        ("/cmd_vel", "geometry_msgs/msg/Twist", 0, 1, ""),
        ("/scan", "sensor_msgs/msg/LaserScan", 1, 1, "best effort"),
    ]
    assert [tuple(a) for a in actions] == [("/gripper_controller/gripper_cmd", "control_msgs/action/GripperCommand")]
    assert services == []


# -- the commands on the local bus -----------------------------------------------------------
def test_list_shows_names_and_with_t_types(capsys, world_config):
    rc, out, _ = run(capsys, world_config, "list", "-t")
    assert rc == 0
    lines = out.splitlines()
    assert "/scan [sensor_msgs/msg/LaserScan]" in lines
    assert "/diff_drive_controller/cmd_vel [geometry_msgs/msg/TwistStamped]" in lines
    assert "/tf_static [tf2_msgs/msg/TFMessage]" in lines
    rc, out, _ = run(capsys, world_config, "list", "--json")
    scan = next(t for t in json.loads(out) if t["name"] == "/scan")
    assert scan == {
        "name": "/scan",
        "type": "sensor_msgs/msg/LaserScan",
        "publishers": 1,
        "subscribers": 0,
        "qos": "best effort",
    }


def test_echo_once_prints_one_message_as_yaml(capsys, world_config):
    rc, out, err = run(capsys, world_config, "echo", "/odom", "--once")
    assert rc == 0, err
    assert out.count("---") == 1
    msg = yaml.safe_load(out.split("---")[0])
    assert msg["header"]["frame_id"] == "odom" and msg["child_frame_id"] == "base_footprint"
    assert set(msg["pose"]) == {"pose", "covariance"}
    assert "/odom [nav_msgs/msg/Odometry] (local bus, sim time: the virtual clock)" in err


def test_echo_json_prints_a_line_per_message(capsys, world_config):
    rc, out, err = run(capsys, world_config, "echo", "scan", "--json", "--count", "2")
    assert rc == 0, err
    lines = out.splitlines()
    assert len(lines) == 2
    scans = [json.loads(line) for line in lines]
    assert all(s["header"]["frame_id"] == "base_scan" for s in scans)
    assert len(scans[0]["ranges"]) == 129 and scans[0]["ranges"][-1] == "..."
    stamps = [s["header"]["stamp"]["sec"] + s["header"]["stamp"]["nanosec"] * 1e-9 for s in scans]
    assert stamps[1] - stamps[0] == pytest.approx(0.2, abs=1e-6)  # 5 Hz in sim time


def test_echo_shortens_images(capsys, world_config):
    rc, out, err = run(capsys, world_config, "echo", "/camera/color/image_raw", "--once", "--no-arr")
    assert rc == 0, err
    image = yaml.safe_load(out.split("---")[0])
    assert image["encoding"] == "rgb8"
    assert image["data"] == f"<sequence<uint8>, length: {image['step'] * image['height']}>"


def test_echo_no_arr_shows_the_frames_of_tf_static(capsys, world_config):
    rc, out, err = run(capsys, world_config, "echo", "/tf_static", "--once", "--no-arr")
    assert rc == 0, err
    msg = yaml.safe_load(out.split("---")[0])
    frames = {(t["header"]["frame_id"], t["child_frame_id"]) for t in msg["transforms"]}
    assert ("base_footprint", "base_link") in frames
    assert any(child.startswith("camera") for _, child in frames)


def test_echo_gives_up_after_its_timeout(capsys, world_config):
    base = "/diff_drive_controller/cmd_vel"
    rc, out, err = run(capsys, world_config, "echo", base, "--timeout", "0.3")
    assert rc == 1 and out == ""
    assert f"nothing publishes {base} yet" in err
    assert f"no message on {base} within 0.3 s" in err


def test_hz_reports_the_rate_in_sim_time(capsys, world_config):
    t0 = time.monotonic()
    rc, out, err = run(capsys, world_config, "hz", "/scan", "--timeout", "3")
    assert rc == 0, err
    reports = [line for line in out.splitlines() if line.startswith("average rate")]
    assert len(reports) == 3, out  # one per second of sim time
    assert all(line == "average rate: 5.000 (sim time)" for line in reports)
    assert "\tmin: 0.200s max: 0.200s std dev: 0.00000s window:" in out
    assert time.monotonic() - t0 < 60


def test_hz_count_and_window(capsys, world_config):
    rc, out, err = run(capsys, world_config, "hz", "/odom", "--count", "20", "--window", "10")
    assert rc == 0, err
    assert out.splitlines()[-2] == "average rate: 30.000 (sim time)"
    assert out.splitlines()[-1].endswith("window: 10")


def test_hz_on_the_wall_clock_says_so(capsys, world_config):
    rc, out, err = run(capsys, world_config, "hz", "/odom", "--count", "10", "--clock", "wall")
    assert rc == 0, err
    assert out.splitlines()[-2].endswith("(wall time)")
    assert "(local bus, wall time)" in err


def test_an_unknown_topic_gets_close_matches_and_exit_2(capsys, world_config):
    rc, out, err = run(capsys, world_config, "echo", "/scna", "--once")
    assert rc == 2 and out == ""
    assert "unknown topic /scna; did you mean /scan?" in err
    rc, _, err = run(capsys, world_config, "hz", "/odometry")
    assert rc == 2 and "did you mean /odom?" in err


def test_action_list_shows_the_robots_actions_with_types(capsys):
    # the default actorbt.yaml: the house world and the robot's subsystems (navstack
    # serves /navigate_to_pose)
    cfg = os.path.join(ROOT, "actorbt.yaml")
    rc = main(["--config", cfg, "action", "list", "-t"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    lines = out.splitlines()
    assert "/arm_controller/follow_joint_trajectory [control_msgs/action/FollowJointTrajectory]" in lines
    assert "/gripper_controller/gripper_cmd [control_msgs/action/GripperCommand]" in lines
    assert "/navigate_to_pose [nav2_msgs/action/NavigateToPose]" in lines
    rc = main(["--config", cfg, "action", "list", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert {"name": "/navigate_to_pose", "type": "nav2_msgs/action/NavigateToPose"} in json.loads(out)
    rc = main(["--config", cfg, "action", "list"])
    out, _ = capsys.readouterr()
    assert "/navigate_to_pose" in out.splitlines() and "[" not in out  # names only


def test_ctrl_c_exits_130_cleanly(world_config):
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_cli.main", "--config", world_config, "topic", "hz", "/scan"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 120)
        assert ready, "no report within 120 s"
        first = proc.stdout.readline()  # the first report: the world runs
        assert first.startswith("average rate:"), first + proc.stderr.read()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert "actorbt: interrupted" in err and "Traceback" not in err


# -- over ROS, against `actorbt sim run --bus ros` -----------------------------------------------
#: a ROS domain of its own (test_ros_common takes 1..100, test_ros_cli 101..200)
ROS_ENV = dict(
    os.environ,
    ROS_DOMAIN_ID=str(201 + os.getpid() % 30),
    PYTHONUNBUFFERED="1",
    ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
)


def actorbt(*argv: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "bt_cli.main", *argv],
        cwd=ROOT,
        env=ROS_ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.fixture(scope="module")
def sim_over_ros():
    pytest.importorskip("rclpy")
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_cli.main", "sim", "run", "--world", "house", "--bus", "ros", "--seconds", "300"],
        cwd=ROOT,
        env=ROS_ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    ready = threading.Event()

    def read():
        for line in proc.stdout:
            if "ready in" in line:
                ready.set()

    threading.Thread(target=read, daemon=True).start()
    try:
        assert ready.wait(120), "actorbt sim run --bus ros did not start"
        yield proc
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def test_over_ros_echo_once_and_list(sim_over_ros):
    proc = actorbt("topic", "echo", "/odom", "--once", "--bus", "ros", "--wait", "30", "--timeout", "60")
    assert proc.returncode == 0, proc.stderr
    msg = yaml.safe_load(proc.stdout.split("---")[0])
    assert msg["header"]["frame_id"] == "odom" and msg["child_frame_id"] == "base_footprint"
    assert "(ROS bus, wall time)" in proc.stderr
    proc = actorbt("topic", "list", "-t", "--bus", "ros", "--wait", "3")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "/scan [sensor_msgs/msg/LaserScan]" in lines and "/tf [tf2_msgs/msg/TFMessage]" in lines
    assert not any("/_action/" in line for line in lines)  # hidden, as ros2 hides them
    # /scan is best effort: heard only with the QoS its publisher offers
    proc = actorbt("topic", "hz", "/scan", "--count", "4", "--bus", "ros", "--wait", "30", "--timeout", "60")
    assert proc.returncode == 0, proc.stderr
    assert "(wall time)" in proc.stdout.splitlines()[-2]


def test_over_ros_action_list_shows_the_simulated_controllers(sim_over_ros):
    proc = actorbt("action", "list", "-t", "--bus", "ros", "--wait", "3")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "/arm_controller/follow_joint_trajectory [control_msgs/action/FollowJointTrajectory]" in lines
    assert "/gripper_controller/gripper_cmd [control_msgs/action/GripperCommand]" in lines
