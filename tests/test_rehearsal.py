"""The real-robot rehearsal, process for process: `actorbt robot` (the simulated robot and
the navstack) in one process, the missions in another with actorbt.real.yaml (no
simulator, no navstack, the wall clock), over DDS, exactly as docs/real-robot.md runs
them against a real TurtleBot3 + OpenManipulator-X.

The mission drives to the north strip of open_floor, looks, grasps the can and places it
on the pallet (about 90 s of wall time). The outcome is judged from the robot side's truth
(`actorbt robot --truth`), not from the mission's word; and a referee node watches the ROS
graph for what the mission process subscribes to: nothing a real robot lacks (every topic
is one the robot side offers, or an action's own topics)."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ACTORBT = [sys.executable, "-m", "bt_cli.main"]
#: a ROS domain of its own (see test_pose_cli for the others)
DOMAIN = "0"
ENV = dict(os.environ, ROS_DOMAIN_ID=DOMAIN, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", PYTHONUNBUFFERED="1")
WORLD, SEED = "open_floor", "0"
PLACE = {"x": 2.0, "y": -2.0, "size_x": 0.6, "size_y": 0.4, "height": 0.12}  # open_floor's pallet
MISSION_TIMEOUT = 300.0  # [s, wall]; the run takes about 90 s
ACTION_TOPIC = re.compile(r"^(?P<action>/.+)/_action/(feedback|status)$")


class GraphReferee:
    """A node of the test's own that lists, every half second, the topics that nodes of
    one process (named ``actorbt_<pid>_...``) subscribe to."""

    def __init__(self) -> None:
        import rclpy

        self.rclpy = rclpy
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=int(DOMAIN))
        self.node = rclpy.create_node("rehearsal_referee", context=self.ctx)
        self.pid: int | None = None
        self.subscribed: dict[str, str] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        while not self._stop.wait(0.5):
            if self.pid is None:
                continue
            prefix = f"actorbt_{self.pid}_"
            for topic, types in self.node.get_topic_names_and_types():
                for info in self.node.get_subscriptions_info_by_topic(topic):
                    if info.node_name.startswith(prefix):
                        self.subscribed[topic] = types[0]

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.ctx)


def offered_by_the_robot_side() -> tuple[dict[str, str], dict[str, str]]:
    """(topic: type, action: type) of `actorbt robot --interfaces --json`."""
    out = subprocess.run(
        [*ACTORBT, "robot", "--world", WORLD, "--interfaces", "--json", "--bus", "local"],
        cwd=REPO,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    offered = json.loads(out.stdout)
    return ({t["name"]: t["type"] for t in offered["topics"]}, {a["name"]: a["type"] for a in offered["actions"]})


def wait_for_line(proc: subprocess.Popen, pattern: str, timeout: float) -> str:
    end = time.monotonic() + timeout
    seen = []
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            if proc.poll() is not None:
                break
            continue
        seen.append(line)
        if pattern in line:
            return line
    raise AssertionError(f"no {pattern!r} from the robot side; it printed:\n{''.join(seen)}")


def on_the_place(pose, place) -> bool:
    x, y, z = pose[:3]
    return (
        abs(x - place["x"]) <= place["size_x"] / 2
        and abs(y - place["y"]) <= place["size_y"] / 2
        and z > place["height"]
    )


@pytest.fixture
def robot_side(tmp_path):
    truth = tmp_path / "truth.json"
    proc = subprocess.Popen(
        [*ACTORBT, "robot", "--world", WORLD, "--seed", SEED, "--truth", str(truth)],
        cwd=REPO,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        wait_for_line(proc, "robot ready", 90)
        yield proc, truth
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def test_the_missions_run_against_the_robot_side_as_on_a_real_robot(robot_side, tmp_path):
    robot, truth_file = robot_side
    topics, actions = offered_by_the_robot_side()
    referee = GraphReferee()
    trace = tmp_path / "run.jsonl"
    try:
        mission = subprocess.Popen(
            [
                *ACTORBT,
                "--config",
                str(REPO / "actorbt.real.yaml"),
                "run",
                "bt_pick_place",
                "--arg",
                "category=can",
                "--arg",
                f"place={json.dumps(PLACE)}",
                "--arg",
                "home={x: 0.0, y: 0.0, yaw: 0.0}",
                "--record",
                str(trace),
            ],
            cwd=REPO,
            env=ENV,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        referee.pid = mission.pid
        try:
            out, _ = mission.communicate(timeout=MISSION_TIMEOUT)
        except subprocess.TimeoutExpired:
            mission.kill()
            out, _ = mission.communicate()
            pytest.fail(f"the mission did not end in {MISSION_TIMEOUT:g} s:\n{out[-4000:]}")
    finally:
        referee.close()
    assert mission.returncode == 0, out[-4000:]

    robot.send_signal(signal.SIGINT)  # the robot side writes its truth as it stops
    robot.wait(timeout=30)
    truth = json.loads(truth_file.read_text())
    cans = [o["pose"] for o in truth["objects"].values() if o["category"] == "can"]
    assert any(on_the_place(pose, truth["place"]) for pose in cans), (truth, out[-3000:])
    assert truth["robot"][:2] == pytest.approx(truth["start"][:2], abs=0.3), "back home"

    # nothing a real robot lacks: each subscription is a topic the robot side offers, or
    # the feedback and status of an action it serves
    assert referee.subscribed, "the referee saw no subscription of the mission process"
    lacking = []
    for topic, type_ in sorted(referee.subscribed.items()):
        action = ACTION_TOPIC.match(topic)
        if action:
            if action["action"] not in actions:
                lacking.append(topic)
        elif topics.get(topic) != type_:
            lacking.append(f"{topic} [{type_}]")
    assert not lacking, f"the mission subscribed to what the robot side does not offer: {lacking}"
    assert {"/tf", "/tf_static", "/odom", "/camera/color/image_raw"} <= set(referee.subscribed)

    # and the recording replays with no robot at all
    replay = subprocess.run(
        [*ACTORBT, "--config", str(REPO / "actorbt.real.yaml"), "replay", str(trace)],
        cwd=REPO,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert replay.returncode == 0, replay.stdout[-3000:] + replay.stderr[-3000:]
