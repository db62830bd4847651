"""The robot's loop never sees the simulator's truth.

The robot's software (actors/, navstack/, trees/) reaches the robot through its topics and
actions only: /scan, /odom, /tf, /tf_static, /joint_states, the camera, /map, the
controllers' actions. The simulator can also give its exact state: SimWorld's methods
(robot_pose, object_pose, link_pose, ...) and the /ground_truth/pose topic (only with
SimWorld(debug_ground_truth=True)). Those are for the referee (demo/episode.py scores the
outcome and measures the localisation error with them), the tests and debugging.
"""

from __future__ import annotations

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
ROBOT_SOFTWARE = ("actors", "navstack", "trees")
#: what the robot's software may not mention: the topic, the flag, and the simulator's
#: truth APIs (SimWorld's methods that read pybullet's state)
FORBIDDEN = re.compile(
    r"ground[_ ]truth|\bSimWorld\b|\.(robot_pose|odom_pose|object_poses?|link_pose|in_gripper|"
    r"state_vector|scan_now|render_camera|set_object_pose)\s*\(",
    re.IGNORECASE,
)


def robot_files():
    for top in ROBOT_SOFTWARE:
        for path in sorted((ROOT / top).rglob("*")):
            if path.suffix in (".py", ".yaml", ".yml") and "__pycache__" not in path.parts:
                yield path


def test_the_robot_software_never_mentions_the_truth():
    files = list(robot_files())
    assert len(files) > 20
    hits = []
    for path in files:
        for n, line in enumerate(path.read_text().splitlines(), 1):
            if FORBIDDEN.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, "the robot's software reads the simulator's truth:\n" + "\n".join(hits)


def test_the_guard_catches_what_it_should():
    for bad in (
        "sub('/ground_truth/pose')",
        "x, y, _ = sim.robot_pose()",
        "world.object_pose('can_1')",
        "SimWorld(rt)",
        "the ground truth pose",
    ):
        assert FORBIDDEN.search(bad), bad
    for fine in ("self.run_actor('get_pose')", "def _odometry(self)", "truth = world.truth"):
        assert not FORBIDDEN.search(fine), fine


def test_a_demo_episode_puts_no_truth_on_the_bus(monkeypatch, tmp_path):
    """With the debug flag off (the default), nothing on the bus carries
    /ground_truth/pose, and the reference mission still succeeds."""
    sim_world = pytest.importorskip("sim.simworld")
    from bt_engine.bus.local import LocalBus
    from demo.episode import run_episode

    assert sim_world.DEBUG_GROUND_TRUTH is False
    topics: set[str] = set()
    publisher, subscribe = LocalBus.publisher, LocalBus.subscribe

    def spy_publisher(self, topic, *args, **kwargs):
        topics.add(topic)
        return publisher(self, topic, *args, **kwargs)

    def spy_subscribe(self, topic, *args, **kwargs):
        topics.add(topic)
        return subscribe(self, topic, *args, **kwargs)

    monkeypatch.setattr(LocalBus, "publisher", spy_publisher)
    monkeypatch.setattr(LocalBus, "subscribe", spy_subscribe)
    ep = run_episode("bt_pick_place", "house", seed=0, category="any", out_dir=tmp_path)
    assert {"/scan", "/odom", "/tf", "/tf_static", "/map", "/diff_drive_controller/cmd_vel", "/initialpose"} <= topics
    assert not [t for t in topics if "ground_truth" in t], sorted(topics)
    assert ep.success, f"{ep.failed_node}: {ep.reason}"
    assert ep.loc_rmse_m < 0.05 and ep.loc_max_m < 0.15
