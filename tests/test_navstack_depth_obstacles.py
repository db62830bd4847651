"""Obstacles below the laser from a depth image (navstack/depth_obstacles.py), on depth
images ray-cast here: the floor, and a low box in front of the robot."""

import math

import numpy as np

from navstack.depth_obstacles import DepthObstacleParams, depth_obstacle_points

W, H, F = 320, 240, 231.0  # the simulated camera's size and focal length [px]
PITCH = math.radians(15)  # looking down


def _camera_in_base() -> np.ndarray:
    """The optical frame (z forward, x right, y down) 9 cm up at the base's front."""
    c, s = math.cos(PITCH), math.sin(PITCH)
    forward, right = np.array([c, 0.0, -s]), np.array([0.0, -1.0, 0.0])
    down = np.cross(forward, right)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([right, down, forward])
    T[:3, 3] = (0.09, 0.0, 0.09)
    return T


def _render(T: np.ndarray, box=None) -> np.ndarray:
    """Depth (along the optical axis) of the floor, and of a box's front face
    (x0, half width, height) when given; NaN where a ray meets nothing within 6 m."""
    u, v = np.meshgrid(np.arange(W) - 159.5, np.arange(H) - 119.5)
    rays = np.stack([u / F, v / F, np.ones_like(u, dtype=float)], axis=-1)  # depth 1 along z
    d_base = rays @ T[:3, :3].T
    o = T[:3, 3]
    depth = np.full((H, W), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_floor = np.where(d_base[..., 2] < 0, -o[2] / d_base[..., 2], np.nan)
        depth = np.where(t_floor < 6.0, t_floor, np.nan)
        if box is not None:
            x0, half, height = box
            t_box = (x0 - o[0]) / d_base[..., 0]
            hit = o + t_box[..., None] * d_base
            on = (t_box > 0) & (np.abs(hit[..., 1]) <= half) & (hit[..., 2] >= 0) & (hit[..., 2] <= height)
            depth = np.where(on & ~(t_box > depth), t_box, depth)
    return depth


def test_the_floor_is_no_obstacle():
    T = _camera_in_base()
    assert len(depth_obstacle_points(_render(T), F, F, 159.5, 119.5, T)) == 0


def test_a_box_lower_than_the_laser_is_seen_where_it_stands():
    T = _camera_in_base()
    pts = depth_obstacle_points(_render(T, box=(0.70, 0.07, 0.04)), F, F, 159.5, 119.5, T)
    assert len(pts) >= 10
    assert np.allclose(pts[:, 0], 0.70, atol=1e-6)  # on its face
    assert np.all(np.abs(pts[:, 1]) <= 0.07 + 1e-9)
    # a flatter one (below min_height) and one beyond max_range are not
    flat = DepthObstacleParams(min_height=0.05)
    assert len(depth_obstacle_points(_render(T, box=(0.70, 0.07, 0.04)), F, F, 159.5, 119.5, T, flat)) == 0
    assert len(depth_obstacle_points(_render(T, box=(1.80, 0.07, 0.04)), F, F, 159.5, 119.5, T)) == 0


def test_what_is_over_the_base_or_nearer_than_min_range_is_left_out():
    T = _camera_in_base()
    depth = _render(T, box=(0.70, 0.07, 0.04))
    depth[100:140, 140:180] = 0.12  # the arm or what it holds, right before the lens
    pts = depth_obstacle_points(depth, F, F, 159.5, 119.5, T)
    assert np.allclose(pts[:, 0], 0.70, atol=1e-6)
    inside = DepthObstacleParams(self_box=(-0.23, 0.8, 0.18))  # a base reaching past the box
    assert len(depth_obstacle_points(depth, F, F, 159.5, 119.5, T, inside)) == 0
