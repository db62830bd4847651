"""``actorbt run --bag``: a short tree in the open_floor world recorded as a rosbag2 folder,
read back with rosbags: the topics and types, message counts equal to what was published
(counted at the publishers), every message deserializes, stamps on the simulator's clock,
the trace equal to --record's, and replay of the bag. Then the one-line errors."""

from __future__ import annotations

import array
import collections
import json
from pathlib import Path

import numpy as np
import pytest

from bt_engine import Runtime
from bt_engine.bus.local import LocalPublisher
from bt_cli.main import main
from bt_cli.config import load_config
from bt_ros.bag import DEFAULT_TOPICS, TRACE_TOPIC, BagRecorder, BagTopic
from bt_ros.cdr import typestore
from bt_ros.compressed import CompressionError, compress_image
from bt_ros.tree_status import status_message

REPO = Path(__file__).resolve().parents[1]
CONFIG = ["--config", str(REPO / "actorbt.yaml")]
#: what the run records: the standard topics and the camera's, which actorbt.yaml adds
RECORDED = DEFAULT_TOPICS + tuple(BagTopic(*t) for t in load_config(REPO / "actorbt.yaml").robot["topics"])
MISSION = """\
name: little_drive
doc: Open the hand, drive a little and rest.
root:
  name: little
  sequence:
    - {name: open hand, do: open}
    - {name: forward, do: mini_walk, with: {distance: 0.2}}
    - {name: rest, wait: 0.5}
"""
EXPECTED_TYPES = {
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/odom": "nav_msgs/msg/Odometry",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/joint_states": "sensor_msgs/msg/JointState",
    "/camera/color/image_raw/compressed": "sensor_msgs/msg/CompressedImage",
    "/camera/camera_info": "sensor_msgs/msg/CameraInfo",
    "/map": "nav_msgs/msg/OccupancyGrid",
    "/actorbt/status": "diagnostic_msgs/msg/DiagnosticArray",
    "/actorbt/trace": "std_msgs/msg/String",
}


def stamp_ns(msg) -> int | None:
    header = getattr(msg, "header", None)
    if header is None and getattr(msg, "transforms", None):
        header = msg.transforms[0].header
    return None if header is None else header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """One run of the little tree with --bag and --record; the publications counted at
    every local publisher meanwhile."""
    folder = tmp_path_factory.mktemp("bag_run")
    mission = folder / "little.yaml"
    mission.write_text(MISSION)
    published: collections.Counter[str] = collections.Counter()
    original = LocalPublisher.publish

    def counting(self, msg):
        published[self.topic] += 1
        return original(self, msg)

    LocalPublisher.publish = counting
    try:
        rc = main(
            [
                *CONFIG,
                "run",
                str(mission),
                "--world",
                "open_floor",
                "--quiet",
                "--bag",
                str(folder / "bag"),
                "--record",
                str(folder / "run.jsonl"),
            ]
        )
    finally:
        LocalPublisher.publish = original
    assert rc == 0
    return folder, published


def read_bag(path: Path):
    from rosbags.rosbag2 import Reader

    with Reader(path) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        counts = {c.topic: c.msgcount for c in reader.connections}
        messages = [(c.topic, c.msgtype, t, raw) for c, t, raw in reader.messages()]
    return types, counts, messages


def test_the_bag_is_a_ros2_mcap_folder_with_every_topic(recorded):
    folder, _ = recorded
    bag = folder / "bag"
    assert sorted(p.name for p in bag.iterdir()) == ["bag.mcap", "metadata.yaml"]
    import yaml

    meta = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["storage_identifier"] == "mcap" and meta["version"] == 9
    assert all(t["topic_metadata"]["serialization_format"] == "cdr" for t in meta["topics_with_message_count"])
    qos = {
        t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"][0]
        for t in meta["topics_with_message_count"]
    }
    assert qos["/map"]["durability"] == "transient_local" == qos["/tf_static"]["durability"]
    assert qos["/scan"]["reliability"] == "best_effort"
    data = (bag / "bag.mcap").read_bytes()
    assert data[:8] == b"\x89MCAP0\r\n" and data[8] == 0x01  # magic, then the header record
    (n,) = np.frombuffer(data[17:21], "<u4")
    assert data[21 : 21 + n] == b"ros2"  # its profile
    types, counts, _ = read_bag(bag)
    assert types == EXPECTED_TYPES
    assert all(counts[t] > 0 for t in EXPECTED_TYPES), counts


def test_the_counts_are_what_was_published(recorded):
    folder, published = recorded
    _, counts, _ = read_bag(folder / "bag")
    recorded_counts = {t.bag_name: counts[t.bag_name] for t in RECORDED}
    published_counts = {t.bag_name: published[t.name] for t in RECORDED}
    assert recorded_counts == published_counts
    # the simulator published them because the bag listened: a few seconds' worth
    assert counts["/odom"] > 100 and counts["/scan"] > 10 and counts["/camera/color/image_raw/compressed"] > 10


def test_every_message_deserializes_and_is_stamped_on_the_sim_clock(recorded):
    import cv2

    folder, _ = recorded
    _, _, messages = read_bag(folder / "bag")
    store = typestore()
    images = statuses = 0
    for topic, msgtype, t, raw in messages:
        msg = store.deserialize_cdr(raw, msgtype)
        stamp = stamp_ns(msg)
        if topic == "/tf" and msg.transforms[0].child_frame_id == "odom":
            stamp = None  # the localiser's map -> odom: post-dated (AMCL's transform tolerance)
        if stamp is not None and topic in ("/odom", "/scan", "/joint_states", "/tf", "/map"):
            assert stamp == t, topic  # stamped when published, recorded as it arrives: one clock
        elif stamp is not None and topic != "/tf_static":
            # the camera's timer stamps its frames with the physics' last step (1/60 s)
            assert 0 <= t - stamp < 1e9 / 60 + 1, topic
        if msgtype.endswith("CompressedImage"):
            assert msg.format == "rgb8; jpeg compressed bgr8"
            image = cv2.imdecode(np.frombuffer(msg.data.tobytes(), np.uint8), cv2.IMREAD_COLOR)
            assert image.shape == (240, 320, 3)
            images += 1
        elif topic == "/actorbt/status":
            (status,) = msg.status
            values = {kv.key: kv.value for kv in status.values}
            assert status.name == f"little_drive/{values['path']}" and status.hardware_id == "actorbt"
            assert status.message in ("RUNNING", "SUCCESS", "FAILURE", "INVALID")
            assert float(values["time"]) * 1e9 == pytest.approx(t, abs=1)
            statuses += 1
    assert images and statuses
    status_paths = [
        store.deserialize_cdr(raw, msgtype).status[0].name
        for topic, msgtype, _, raw in messages
        if topic == "/actorbt/status"
    ]
    assert status_paths[:2] == ["little_drive/little", "little_drive/little/open hand"]


def test_the_trace_in_the_bag_is_the_recorded_trace_and_replays(recorded, capsys):
    folder, _ = recorded
    _, _, messages = read_bag(folder / "bag")
    store = typestore()
    lines = [store.deserialize_cdr(raw, msgtype).data for topic, msgtype, _, raw in messages if topic == TRACE_TOPIC]
    jsonl = (folder / "run.jsonl").read_text().splitlines()

    def comparable(line: str) -> dict:
        record = json.loads(line)
        record.pop("recorded", None)  # the wall-clock second each recorder opened
        return record

    assert [comparable(x) for x in lines] == [comparable(x) for x in jsonl]
    assert main([*CONFIG, "replay", str(folder / "bag")]) == 0
    assert "OK" in capsys.readouterr().out


def test_a_bag_folder_that_is_not_new_is_one_clear_line(tmp_path, capsys):
    full = tmp_path / "full"
    full.mkdir()
    (full / "x").write_text("")
    rc = main([*CONFIG, "run", "demo_patrol", "--world", "none", "--bag", str(full)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "exists and is not empty" in err[0]
    (tmp_path / "file").write_text("")
    rc = main([*CONFIG, "run", "demo_patrol", "--world", "none", "--bag", str(tmp_path / "file")])
    assert rc == 2 and "that is a file" in capsys.readouterr().err


def test_a_bag_without_a_trace_says_so(tmp_path, capsys):
    rt = Runtime(clock="virtual")
    try:
        BagRecorder(rt, tmp_path / "empty").close()  # an empty folder may be written to
    finally:
        rt.close()
    rc = main([*CONFIG, "replay", str(tmp_path / "empty")])
    err = capsys.readouterr().err
    assert rc == 2 and "holds no /actorbt/trace" in err


def test_the_status_message_says_node_status_and_time():
    msg = status_message("bt_search", "search/look", "RUNNING", "FAILURE", 12.25, run=3, depth=1)
    (status,) = msg.status
    assert (status.name, status.message, status.level) == ("bt_search/search/look", "FAILURE", b"\x02")
    assert {kv.key: kv.value for kv in status.values} == {
        "tree": "bt_search",
        "path": "search/look",
        "previous": "RUNNING",
        "run": "3",
        "depth": "1",
        "time": "12.25",
    }
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (12, 250_000_000)
    levels = {
        new: status_message("t", "p", "INVALID", new, 0.0).status[0].level
        for new in ("RUNNING", "SUCCESS", "FAILURE", "INVALID")
    }
    assert levels == {"RUNNING": b"\x00", "SUCCESS": b"\x00", "FAILURE": b"\x02", "INVALID": b"\x03"}


def test_images_are_compressed_as_image_transport_does():
    import cv2
    from sensor_msgs.msg import Image

    rgb = np.zeros((8, 6, 3), np.uint8)
    rgb[..., 0] = 200  # red
    msg = Image(height=8, width=6, encoding="rgb8", step=18, data=array.array("B", rgb.tobytes()))
    out = compress_image(msg)
    assert out.format == "rgb8; jpeg compressed bgr8"
    bgr = cv2.imdecode(np.frombuffer(bytes(out.data), np.uint8), cv2.IMREAD_COLOR)
    assert abs(int(bgr[4, 3, 2]) - 200) < 8 and int(bgr[4, 3, 0]) < 8  # red stays red
    depth = np.arange(12, dtype="<u2").reshape(3, 4) * 1000
    msg = Image(height=3, width=4, encoding="16UC1", step=8, data=array.array("B", depth.tobytes()))
    out = compress_image(msg)
    assert out.format == "16UC1; png compressed 16UC1"
    back = cv2.imdecode(np.frombuffer(bytes(out.data), np.uint8), cv2.IMREAD_UNCHANGED)
    assert (back == depth).all()  # PNG: lossless
    with pytest.raises(CompressionError, match="32FC1"):
        compress_image(Image(height=1, width=1, encoding="32FC1", step=4, data=array.array("B", bytes(4))))
