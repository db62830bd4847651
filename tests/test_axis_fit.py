"""actors/axis_fit.py: the axis of a cylinder in any pose from the surface points seen."""

import math

import numpy as np
import pytest

from actors import axis_fit


CAMERA = np.array([0.0, 0.0, 0.1])


def _seen_cylinder(point, direction, radius=0.033, length=0.12, noise=0.0, seed=0, cap=False):
    """Points of a cylinder's side (and optionally one end cap) as CAMERA sees them, laid
    out as an image grid: rows along the axis, columns round the half facing the camera."""
    a = np.asarray(direction, float)
    a /= np.linalg.norm(a)
    u, v = axis_fit._basis(a)
    to_camera = CAMERA - np.asarray(point, float)
    ang0 = math.atan2(to_camera @ v, to_camera @ u)  # the normal facing the camera
    ang = ang0 + np.linspace(-1.3, 1.3, 40)
    s = np.linspace(0.0, length, 50)
    grid = (
        np.asarray(point, float)
        + s[:, None, None] * a
        + radius * (np.cos(ang)[None, :, None] * u + np.sin(ang)[None, :, None] * v)
    )
    if cap:
        rr = np.linspace(0.0, radius, 12)
        disc = (
            np.asarray(point, float)
            + length * a
            + rr[:, None, None] * (np.cos(ang)[None, :, None] * u + np.sin(ang)[None, :, None] * v)
        )
        grid = np.concatenate([grid, disc[::-1]], axis=0)
    if noise:
        grid = grid + np.random.default_rng(seed).normal(0, noise, grid.shape)
    return grid


@pytest.mark.parametrize("direction", [(0, 0, 1), (1, 0, 0), (0.6, 0.8, 0), (0.3, 0.2, 0.9), (0, 0.5, 0.8)])
def test_the_axis_is_found_in_any_pose(direction):
    point = np.array([2.0, 1.0, 0.033])
    grid = _seen_cylinder(point, direction)
    fit = axis_fit.fit_axis(*axis_fit.surface_normals(grid), 0.033, view_from=CAMERA)
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    assert math.degrees(math.acos(min(1.0, abs(float(fit.direction @ d))))) < 1.0
    # the fitted point lies on the true axis
    off = (fit.point - point) - ((fit.point - point) @ d) * d
    assert np.linalg.norm(off) < 1e-3
    assert fit.rms < 1e-3


def test_an_end_cap_does_not_pull_the_axis():
    d = np.array([0.6, 0.8, 0.0])
    grid = _seen_cylinder([1.0, 1.0, 0.033], d, cap=True)
    cands = axis_fit.axis_candidates(*axis_fit.surface_normals(grid))
    assert any(math.degrees(math.acos(min(1.0, abs(float(c @ d))))) < 2.0 for c in cands)


def test_depth_noise_costs_a_few_degrees_only():
    d = np.array([0.0, 1.0, 0.0])
    grid = _seen_cylinder([1.0, 1.0, 0.033], d, noise=0.0015, seed=3)
    fit = axis_fit.fit_axis(*axis_fit.surface_normals(grid), 0.033, view_from=CAMERA)
    assert math.degrees(math.acos(min(1.0, abs(float(fit.direction @ d))))) < 3.0
    assert 0.0008 < fit.rms < 0.003


def test_too_few_points_give_no_axis():
    grid = np.full((5, 5, 3), np.nan)
    assert axis_fit.fit_axis(*axis_fit.surface_normals(grid), 0.03, np.zeros(3)) is None
