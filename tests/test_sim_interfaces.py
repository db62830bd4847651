"""`actorbt sim interfaces` (issue [senses]): what the simulated robot offers, with ROS type
names, read from the bus of a running world (so it cannot drift from what the world does)."""

from __future__ import annotations

import json
import pathlib

import pytest

from bt_cli.main import main

REPO = pathlib.Path(__file__).resolve().parents[1]


def interfaces(capsys, *argv):
    rc = main(["--config", str(REPO / "actorbt.yaml"), "sim", "interfaces", *argv])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return out


@pytest.fixture(scope="module")
def offered():
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["--config", str(REPO / "actorbt.yaml"), "sim", "interfaces", "--world", "house", "--json"])
    assert rc == 0
    return json.loads(buf.getvalue())


def test_the_robots_sensors_and_actuators_with_ros_types(offered):
    topics = {t["name"]: t for t in offered["topics"]}
    assert topics["/scan"]["type"] == "sensor_msgs/msg/LaserScan"
    assert topics["/scan"]["direction"] == "publishes"
    assert topics["/scan"]["qos"] == "best effort"  # as the LDS driver offers it
    # ROS 2 Jazzy's diff_drive_controller: ~/cmd_vel, stamped only
    assert topics["/diff_drive_controller/cmd_vel"] == {
        "name": "/diff_drive_controller/cmd_vel",
        "type": "geometry_msgs/msg/TwistStamped",
        "direction": "subscribes",
        "qos": "",
    }
    assert "/cmd_vel" not in topics
    assert "/initialpose" not in topics, "the pose estimate is the user's, not the robot's"
    expected = {
        "/odom": "nav_msgs/msg/Odometry",
        "/tf": "tf2_msgs/msg/TFMessage",
        "/tf_static": "tf2_msgs/msg/TFMessage",
        "/joint_states": "sensor_msgs/msg/JointState",
        "/map": "nav_msgs/msg/OccupancyGrid",
        "/camera/color/image_raw": "sensor_msgs/msg/Image",
        "/camera/depth/image_raw": "sensor_msgs/msg/Image",
        "/camera/camera_info": "sensor_msgs/msg/CameraInfo",
        "/imu_broadcaster/imu": "sensor_msgs/msg/Imu",
    }
    for name, type_ in expected.items():
        assert topics[name]["type"] == type_ and topics[name]["direction"] == "publishes", name
    assert topics["/tf_static"]["qos"] == "reliable, transient local"
    assert offered["world"] == "house" and offered["seed"] == 0
    assert offered["services"] == []


def test_the_controllers_actions(offered):
    actions = {a["name"]: a["type"] for a in offered["actions"]}
    assert actions.get("/arm_controller/follow_joint_trajectory") == "control_msgs/action/FollowJointTrajectory"
    assert actions.get("/gripper_controller/gripper_cmd") == "control_msgs/action/GripperCommand"


def test_the_text_form_is_a_table(capsys):
    out = interfaces(capsys, "--world", "open_floor")
    assert out.startswith("World open_floor (seed 0): what the simulated robot offers")
    lines = out.splitlines()
    published = lines.index("Topics it publishes:")
    subscribed = lines.index("Topics it subscribes to:")
    scan = next(line for line in lines[published:subscribed] if line.split()[0] == "/scan")
    assert scan.split()[1:] == ["sensor_msgs/msg/LaserScan", "best", "effort"]
    assert any(
        line.split()[:2] == ["/diff_drive_controller/cmd_vel", "geometry_msgs/msg/TwistStamped"]
        for line in lines[subscribed:]
    )
    assert "Services it serves: none" in lines


def test_the_list_is_read_from_the_bus(capsys, monkeypatch):
    """A topic the world starts publishing shows up without anyone editing a list."""
    from std_msgs.msg import String

    import sim.topics

    original = sim.topics.SimTopics.__init__

    def with_extra(self, sim_, rt):
        original(self, sim_, rt)
        self.pub_extra = rt.bus.publisher("/extra/status", String)

    monkeypatch.setattr(sim.topics.SimTopics, "__init__", with_extra)
    data = json.loads(interfaces(capsys, "--json"))
    assert {
        "name": "/extra/status",
        "type": "std_msgs/msg/String",
        "direction": "publishes",
        "qos": "reliable",
    } in data["topics"]


def test_the_real_robots_configuration_differs_only_where_it_must():
    """docs/real-robot.md: actorbt.real.yaml is actorbt.yaml without the simulator and the
    navstack (Nav2 and AMCL stand in), on ROS and the wall clock."""
    from bt_cli.config import load_config

    sim, real = load_config(REPO / "actorbt.yaml"), load_config(REPO / "actorbt.real.yaml")
    assert real.world is None and real.simulator is None
    assert real.transport == "ros" and real.clock == "wall"
    assert "navstack" not in real.subsystems
    assert real.subsystems == {k: v for k, v in sim.subsystems.items() if k != "navstack"}
    assert real.trees == sim.trees
    assert set(real.plugins) <= set(sim.plugins)
    assert "docs/real-robot.md" in (REPO / "actorbt.real.yaml").read_text()
