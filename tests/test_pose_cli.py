"""`actorbt pose init X Y YAW` (bt_ros/pose_cli.py): one /initialpose over ROS, as
RViz's "2D Pose Estimate" sends it, heard by a subscription in this test; no subscriber is
exit status 1, the local bus exit status 2 with where to give the pose instead. Also the
navigation's set_initial_pose actor, which gives it from a runtime on any bus."""

from __future__ import annotations

import math
import os
import textwrap
import threading

import pytest

from bt_cli.main import main
from bt_ros.pose_cli import RVIZ_STD_XY, RVIZ_STD_YAW, initial_pose_msg

#: a ROS domain of its own (test_ros_common takes 1..100, test_ros_cli 101..200,
#: test_topic_cli 201..230)
DOMAIN = str(231 + os.getpid() % 2)


def config(tmp_path, transport: str) -> str:
    """An actorbt.yaml with nothing to start: pose init needs only the transport."""
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text(
        textwrap.dedent(f"""\
        subsystems: {{}}
        trees: null
        world: null
        transport: {transport}
        """)
    )
    return str(cfg)


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


# -- the message -----------------------------------------------------------------------------
def test_the_message_is_rvizs_2d_pose_estimate():
    msg = initial_pose_msg(1.0, -2.0, math.pi / 2)
    assert msg.header.frame_id == "map"
    p = msg.pose.pose
    assert (p.position.x, p.position.y, p.position.z) == (1.0, -2.0, 0.0)
    assert yaw_of(p.orientation) == pytest.approx(math.pi / 2)
    cov = list(msg.pose.covariance)
    assert (RVIZ_STD_XY, RVIZ_STD_YAW) == (0.5, pytest.approx(0.2618, abs=1e-4))
    assert cov[0] == cov[7] == pytest.approx(0.25) and cov[35] == pytest.approx((math.pi / 12) ** 2)
    assert sum(1 for c in cov if c) == 3  # the rest of the 6x6 is zero, as RViz leaves it


# -- the command -----------------------------------------------------------------------------
def test_on_the_local_bus_it_says_where_to_give_the_pose(tmp_path, capsys):
    rc = main(["--config", config(tmp_path, "local"), "pose", "init", "1", "2", "-1.57"])
    out, err = capsys.readouterr()
    assert rc == 2 and out == ""
    assert "only this command's own runtime" in err
    assert "`set_initial_pose 1 2 -1.57`" in err and "actorbt rcall set_initial_pose" in err
    assert "--bus ros" in err


@pytest.fixture
def ros_domain(monkeypatch):
    pytest.importorskip("rclpy")
    monkeypatch.setenv("ROS_DOMAIN_ID", DOMAIN)
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    return int(DOMAIN)


def test_over_ros_a_subscriber_gets_the_pose_and_covariance(tmp_path, capsys, ros_domain):
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from rclpy.qos import QoSProfile

    from bt_ros.host import RosHost

    heard: list = []
    arrived = threading.Event()

    def on_pose(msg) -> None:  # the executor thread
        heard.append(msg)
        arrived.set()

    with RosHost("amcl-stand-in", domain_id=ros_domain) as host:
        node = host.create_node("amcl", lean=True)
        host.call(node.create_subscription, PoseWithCovarianceStamped, "/initialpose", on_pose, QoSProfile(depth=10))
        # transport: ros in actorbt.yaml, as actorbt.real.yaml says it (no --bus)
        rc = main(
            [
                "--config",
                config(tmp_path, "ros"),
                "pose",
                "init",
                "1.5",
                "-2",
                "-1.57",
                "--std-xy",
                "0.2",
                "--wait",
                "20",
            ]
        )
        out, err = capsys.readouterr()
        assert rc == 0, err
        assert arrived.wait(5), "the pose never arrived"
    assert len(heard) == 1
    msg = heard[0]
    assert msg.header.frame_id == "map" and msg.header.stamp.sec > 0  # stamped, as RViz does
    p = msg.pose.pose
    assert (p.position.x, p.position.y) == (1.5, -2.0)
    assert yaw_of(p.orientation) == pytest.approx(-1.57)
    cov = msg.pose.covariance
    assert cov[0] == cov[7] == pytest.approx(0.04) and cov[35] == pytest.approx((math.pi / 12) ** 2)
    assert out.startswith("/initialpose: x 1.500 m, y -2.000 m, yaw -1.570 rad (-90.0 deg) in map")
    assert out.rstrip().endswith("to /amcl")


def test_over_ros_with_no_subscriber_it_says_so_and_exits_1(tmp_path, capsys, ros_domain):
    rc = main(["--config", config(tmp_path, "local"), "pose", "init", "1", "1", "0", "--bus", "ros", "--wait", "0.5"])
    out, err = capsys.readouterr()
    assert rc == 1 and out == ""
    assert "nobody subscribes to /initialpose after 0.5 s: is AMCL / the navstack running?" in err


def test_a_standard_deviation_is_not_negative(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--config", config(tmp_path, "ros"), "pose", "init", "1", "1", "0", "--std-yaw", "-0.1"])
    assert stop.value.code == 2
    assert "expected a standard deviation >= 0, got -0.1" in capsys.readouterr().err


# -- the actor -------------------------------------------------------------------------------
def test_set_initial_pose_publishes_initialpose_in_the_map_frame():
    from geometry_msgs.msg import PoseWithCovarianceStamped

    from actors.navigation import Navigation
    from bt_engine import Runtime

    heard: list = []
    with Runtime() as rt:
        rt.add_subsystem("navigation", Navigation)
        rt.run_on_hub(rt.bus.subscribe, "/initialpose", PoseWithCovarianceStamped, heard.append)
        assert rt.call("set_initial_pose", 2.0, 3.0, math.pi) == (2.0, 3.0, math.pi)
        rt.call("set_initial_pose", 0.0, 0.0, 0.0, std_xy=0.1, std_yaw=0.05)
    assert len(heard) == 2
    first, second = heard
    assert first.header.frame_id == "map"
    assert (first.pose.pose.position.x, first.pose.pose.position.y) == (2.0, 3.0)
    assert abs(yaw_of(first.pose.pose.orientation)) == pytest.approx(math.pi)
    assert first.pose.covariance[0] == first.pose.covariance[7] == pytest.approx(0.25)
    assert first.pose.covariance[35] == pytest.approx(0.2618**2)
    assert second.pose.covariance[0] == pytest.approx(0.01)
    assert second.pose.covariance[35] == pytest.approx(0.0025)
