"""navstack.obstacle_memory: the depth camera's points, kept while out of its view."""

from __future__ import annotations

import math

import numpy as np

from navstack.obstacle_memory import ObstacleMemory

K = (300.0, 0.0, 160.0, 0.0, 300.0, 120.0, 0.0, 0.0, 1.0)  # 320 x 240, 56 degrees across


def camera_at(x: float, y: float, yaw: float, z: float = 0.2) -> np.ndarray:
    """The optical frame (z ahead, x right, y down) of a level camera at (x, y, z) facing yaw."""
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:3, 0] = (s, -c, 0.0)  # right
    T[:3, 1] = (0.0, 0.0, -1.0)  # down
    T[:3, 2] = (c, s, 0.0)  # ahead
    T[:3, 3] = (x, y, z)
    return T


def memory() -> ObstacleMemory:
    return ObstacleMemory(keep=60.0, min_range=0.25, max_range=1.5)


def test_a_point_out_of_view_is_kept_and_one_in_view_that_is_gone_is_forgotten():
    mem = memory()
    mem.update(np.array([[1.0, 0.0], [1.0, 1.0]]), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=0.0)
    assert len(mem) == 2
    # the camera turns left by 20 degrees: both are in view, and gone
    mem.update(np.zeros((0, 2)), camera_at(0.0, 0.0, math.radians(20)), K, 320, 240, now=1.0)
    assert len(mem) == 0
    mem.update(np.array([[1.0, 0.0]]), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=2.0)
    # the camera looks the other way: the point is behind it, and stays
    mem.update(np.zeros((0, 2)), camera_at(0.0, 0.0, math.pi), K, 320, 240, now=3.0)
    assert mem.points().tolist() == [[1.0, 0.0]]


def test_a_point_too_near_for_the_camera_is_kept():
    mem = memory()
    mem.update(np.array([[0.6, 0.0]]), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=0.0)
    # driven up to it: 10 cm from the camera, nearer than min_range
    mem.update(np.zeros((0, 2)), camera_at(0.5, 0.0, 0.0), K, 320, 240, now=1.0)
    assert len(mem) == 1


def test_old_and_far_points_are_forgotten():
    mem = memory()
    mem.update(np.array([[-1.0, 0.0]]), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=0.0)
    mem.update(np.array([[-1.0, 0.5]]), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=30.0)
    mem.update(np.zeros((0, 2)), camera_at(0.0, 0.0, 0.0), K, 320, 240, now=61.0)
    assert mem.points().tolist() == [[-1.0, 0.5]]
    mem.update(np.zeros((0, 2)), camera_at(3.0, 0.0, 0.0), K, 320, 240, now=62.0)  # 4 m away now
    assert len(mem) == 0


def test_one_point_is_kept_per_cell():
    mem = memory()
    pts = np.array([[-1.001, 0.001], [-1.002, 0.002], [-1.2, 0.0]])
    mem.update(pts, camera_at(0.0, 0.0, 0.0), K, 320, 240, now=0.0)
    assert len(mem) == 2
