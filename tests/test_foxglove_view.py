"""The live Foxglove view: a real Foxglove SDK server on a free port, a WebSocket client
(tests/foxglove_client.py) that checks what it advertises and what it sends, the scene
built from actor calls, the shipped layout, and the errors of a taken port."""

from __future__ import annotations

import io
import json
import math
import socket
import time
from pathlib import Path
from typing import Any

import pytest

from bt_engine import Runtime, SubSystem, actor
from bt_cli.main import main
from bt_cli.config import load_config
from bt_ros.bag import DEFAULT_TOPICS, BagTopic
from bt_ros.cdr import typestore
from bt_ros.foxglove_layout import layout_json
from bt_ros.foxglove_scene import Body, Detection, Goal, Scene, detections_in, goal_of
from bt_ros.foxglove_view import PATH_TOPIC, SCENE_TOPIC, FoxgloveView
from bt_ros.live_options import FoxgloveError, LiveOptions
from bt_engine.trees import TraceRecorder, TreeHost
from tests.foxglove_client import FoxgloveClient

REPO = Path(__file__).resolve().parents[1]
#: the reference robot's actorbt.yaml: its camera topics and its body
ROBOT = load_config(REPO / "actorbt.yaml").robot
TOPICS = DEFAULT_TOPICS + tuple(BagTopic(*t) for t in ROBOT["topics"])
ROS_CHANNELS = {t.bag_name: t.bag_type for t in TOPICS}


class Robotish(SubSystem):
    """What the view watches for: a result that is a detection, an action-shaped goal."""

    @actor
    def watch(self) -> dict:
        return {"category": "can", "x": 1.5, "y": -0.5, "z": 0.1, "confidence": 0.9}

    @actor
    def navigate(self, goal: Any) -> bool:
        return True


@pytest.fixture
def view():
    rt = Runtime(clock="virtual")
    rt.add_subsystem("robot", Robotish)
    v = FoxgloveView(rt, port=0, topics=TOPICS, body=Body(*ROBOT["body"]))
    try:
        yield v
    finally:
        v.close()
        rt.close()


@pytest.fixture
def client(view):
    c = FoxgloveClient(view.port)
    c.wait_for_channels(set(ROS_CHANNELS) | {SCENE_TOPIC, PATH_TOPIC})
    yield c
    c.close()


def wait_until(condition, timeout: float = 10.0) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.02)


def listening(port: int) -> set[str]:
    """The local addresses (hex, as /proc/net/tcp* shows them) listening on ``port``."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:
                found.add(address)
    return found


def test_it_advertises_the_robot_topics_the_scene_and_the_path(view, client):
    assert client.server_info["name"] == "actorbt"
    assert "time" in client.server_info["capabilities"]  # the robot's clock is the view's
    for topic, type_name in ROS_CHANNELS.items():
        channel = client.channels[topic]
        assert (channel["encoding"], channel["schemaEncoding"], channel["schemaName"]) == ("cdr", "ros2msg", type_name)
        assert channel["schema"].splitlines()[0]  # the definition text, dependencies appended
    assert client.channels[SCENE_TOPIC]["schemaName"] == "foxglove.SceneUpdate"
    assert client.channels[PATH_TOPIC]["schemaName"] == "foxglove.PosesInFrame"
    assert {"/map", "/scan", "/tf", "/tf_static", "/camera/color/image_raw/compressed", "/actorbt/status"} <= set(
        client.channels
    )


def test_it_listens_on_this_machine_only(view):
    if not Path("/proc/net/tcp").exists():
        pytest.skip("no /proc/net/tcp here")
    assert view.url == f"ws://127.0.0.1:{view.port}"
    assert listening(view.port) == {"0100007F"}  # 127.0.0.1, not 0.0.0.0


def test_a_topic_is_subscribed_while_a_client_watches_it_and_sent_as_cdr(view, client):
    from sensor_msgs.msg import LaserScan

    rt = view.rt
    assert rt.bus.subscription_count("/scan") == 0  # nobody watches: the lidar need not cast
    client.subscribe(7, "/scan")
    wait_until(lambda: rt.bus.subscription_count("/scan") == 1)
    pub = rt.bus.publisher("/scan", LaserScan, "sensor")
    scan = LaserScan(angle_min=-math.pi, angle_max=math.pi, range_max=3.5, ranges=[1.0, 2.0, 3.0])
    scan.header.frame_id = "base_scan"
    rt.run_on_hub(pub.publish, scan)
    log_time, payload = client.message(7)
    got = typestore().deserialize_cdr(payload, "sensor_msgs/msg/LaserScan")
    assert list(got.ranges) == [1.0, 2.0, 3.0] and got.header.frame_id == "base_scan"
    assert log_time == int(round(rt.now() * 1e9))  # the runtime clock
    client.unsubscribe(7)
    wait_until(lambda: rt.bus.subscription_count("/scan") == 0)


def test_detections_and_goals_from_actor_calls_become_scene_entities(view, client):
    from nav2_msgs.action import NavigateToPose

    rt = view.rt
    host = TreeHost(rt)
    trace = io.StringIO()
    # a trace recorder opened after the view passes the calls on to it
    with TraceRecorder(trace, host, tree="none", transactions=True):
        assert rt.call("watch")["category"] == "can"
        goal = NavigateToPose.Goal()
        goal.pose.header.frame_id = "map"
        goal.pose.pose.position.x, goal.pose.pose.position.y = 2.0, 1.0
        goal.pose.pose.orientation.z, goal.pose.pose.orientation.w = math.sin(0.25), math.cos(0.25)
        assert rt.call("navigate", goal) is True
    assert '"type":"txn"' in trace.getvalue()
    assert view.scene.detections == [Detection("can", 1.5, -0.5, 0.1)]
    (g,) = view.scene.goals
    assert (g.x, g.y, g.frame) == (2.0, 1.0, "map") and g.yaw == pytest.approx(0.5)
    client.subscribe(3, SCENE_TOPIC)
    for _ in range(100):  # the subscription lands on the server's thread: send until it is there
        rt.run_on_hub(view._send_scene)
        try:
            _, payload = client.message(3, timeout=0.2)
            break
        except TimeoutError:
            continue
    else:
        pytest.fail("no scene update arrived")
    for entity in (b"robot", b"base_footprint", b"detection/0", b"can", b"goal/0"):
        assert entity in payload  # protobuf keeps strings as they are


def test_closing_the_view_gives_the_hooks_back():
    rt = Runtime(clock="virtual")
    try:
        v = FoxgloveView(rt, port=0)
        assert rt.recorder is not None
        v.close()
        assert rt.recorder is None
        v.close()  # twice is fine
    finally:
        rt.close()


def test_scene_rules():
    assert list(detections_in([{"found": {"category": "bottle", "x": 1, "y": 2}}, {"x": 1}])) == [
        Detection("bottle", 1.0, 2.0)
    ]
    assert list(detections_in({"category": "can", "x": float("nan"), "y": 0.0})) == []
    assert goal_of(()) is None and goal_of((3.0, 4.0)) is None
    scene = Scene(Body(0.28, 0.31, 0.14, x=-0.06))
    assert scene.add_detection(Detection("can", 1.0, 1.0))
    assert scene.add_detection(Detection("can", 1.1, 1.0))  # the same can, seen better
    assert not scene.add_detection(Detection("can", 1.1, 1.0))  # nothing new
    assert scene.add_detection(Detection("bottle", 1.1, 1.0))  # another object
    assert [d.category for d in scene.detections] == ["can", "bottle"]
    assert scene.add_odometry(0.0, 0.0, 0.0)
    assert not scene.add_odometry(0.005, 0.0, 0.0)  # too close to the last pose
    assert scene.add_odometry(0.05, 0.0, 0.0)
    scene.add_goal(Goal(1.0, 2.0, 0.0))
    update = scene.update(1.0).encode()  # the messages are opaque: look at their bytes
    for entity in (b"robot", b"detection/0", b"detection/1", b"goal/0"):
        assert entity in update
    assert b"detection/2" not in update and b"goal/1" not in update
    assert len(scene.path) == 2 and scene.path_message(1.0).encode()


def test_without_a_body_the_scene_draws_no_robot():
    scene = Scene()
    scene.add_detection(Detection("can", 1.0, 1.0))
    update = scene.update(1.0).encode()
    assert b"detection/0" in update and b"robot" not in update


def test_the_shipped_layout_is_the_generated_one_and_names_the_served_topics():
    shipped = (REPO / "docs" / "foxglove_layout.json").read_text()
    assert shipped == layout_json(), "regenerate: python -m bt_ros.foxglove_layout docs/foxglove_layout.json"
    text = json.dumps(json.loads(shipped))
    served = set(ROS_CHANNELS) | {SCENE_TOPIC, PATH_TOPIC}
    for topic in (
        "/map",
        "/scan",
        SCENE_TOPIC,
        PATH_TOPIC,
        "/camera/color/image_raw/compressed",
        "/camera/camera_info",
        "/actorbt/status",
    ):
        assert f'"{topic}' in text and topic in served


def test_a_taken_port_is_one_clear_line(capsys):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(FoxgloveError, match="in use"):
            LiveOptions(foxglove=port).check()
        rt = Runtime(clock="virtual")
        try:
            with pytest.raises(FoxgloveError, match=f"127.0.0.1:{port}"):
                FoxgloveView(rt, port=port)
            assert rt.recorder is None
        finally:
            rt.close()
        # before any world is built
        rc = main(
            ["--config", str(REPO / "actorbt.yaml"), "run", "demo_patrol", "--world", "none", "--foxglove", str(port)]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "the port is in use" in err[0], err


def test_a_port_out_of_range_is_refused_by_the_parser(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--config", str(REPO / "actorbt.yaml"), "run", "demo_patrol", "--foxglove", "70000"])
    assert stop.value.code == 2
    assert "expected a TCP port from 0 to 65535" in capsys.readouterr().err
