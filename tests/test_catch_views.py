"""A grasp that failed is retried from another side (actors/catch.py)."""
from __future__ import annotations

import math

from actors.catch import fresh_views_first


def test_the_side_of_a_failed_grasp_comes_last():
    poses = [(0.0, 0.0, math.radians(a)) for a in (0, 30, -30, 60)]
    obj = (1.4, 0.07)
    assert fresh_views_first(poses, obj, []) == poses
    failed = [(1.42, 0.05, math.radians(10))]                  # this object, from 10 degrees
    assert [round(math.degrees(p[2])) for p in fresh_views_first(poses, obj, failed)] == [-30, 60, 0, 30]
    elsewhere = [(3.0, 2.0, math.radians(10))]                 # another object's failure
    assert fresh_views_first(poses, obj, elsewhere) == poses
