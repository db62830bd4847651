"""Box fitting helpers (actors/perception_box.py)."""

from __future__ import annotations

import numpy as np

from actors.perception_box import _densest


def test_a_face_seen_squarely_is_placed_where_its_points_crowd_not_at_the_nearest():
    """Its points' depth scatters a few millimetres from a metre away: the nearest of them
    is a centimetre or more short of the face (house_hard 2044: an upright carton on a
    table, its centre put short). A face seen at a grazing angle behind it hardly moves it."""
    rng = np.random.default_rng(7)
    noise = 0.004
    face = 1.0 + rng.normal(0.0, noise, 300)  # the face seen squarely, at 1 m
    grazing = rng.uniform(1.0, 1.07, 40)  # the other face, running away behind it
    c = np.concatenate([face, grazing])
    assert c.min() < 1.0 - 2.5 * noise  # the nearest point: noise
    assert abs(_densest(c, noise) - 1.0) < 0.0015
    assert abs(_densest(face, noise) - 1.0) < 0.001
