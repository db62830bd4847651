"""The transform tree (planning.tf_buffer): chains, inverses, interpolation, statics and
clear errors."""

from __future__ import annotations

import math
from types import SimpleNamespace as NS

import numpy as np
import pytest

from planning.tf_buffer import (
    TransformBuffer,
    TransformError,
    interpolate,
    invert,
    matrix_quaternion,
    planar,
    pose2d,
    quaternion_matrix,
    transform_matrix,
)


def tree() -> TransformBuffer:
    tf = TransformBuffer()
    tf.set("map", "odom", planar(1.0, 0.0, math.pi / 2), t=0.0)
    tf.set("map", "odom", planar(1.0, 0.0, math.pi / 2), t=10.0)
    tf.set("odom", "base_footprint", planar(0.0, 0.0, 0.0), t=0.0)
    tf.set("odom", "base_footprint", planar(2.0, 0.0, 0.0), t=2.0)
    tf.set("base_footprint", "base_scan", transform_matrix((-0.064, 0, 0.122), (0, 0, 0, 1)), static=True)
    return tf


def test_a_chain_composes_parent_to_child():
    x, y, yaw = pose2d(tree().lookup("map", "base_footprint", 2.0))
    assert (x, y, yaw) == pytest.approx((1.0, 2.0, math.pi / 2))


def test_the_reverse_lookup_is_the_inverse():
    tf = tree()
    np.testing.assert_allclose(
        tf.lookup("base_scan", "map", 1.0), invert(tf.lookup("map", "base_scan", 1.0)), atol=1e-12
    )


def test_times_between_samples_are_interpolated_and_statics_hold_at_any_time():
    tf = tree()
    assert pose2d(tf.lookup("odom", "base_scan", 1.0))[0] == pytest.approx(1.0 - 0.064)
    assert pose2d(tf.lookup("odom", "base_footprint", None))[0] == pytest.approx(2.0)


def test_a_time_outside_the_history_is_an_error_that_says_so():
    with pytest.raises(TransformError, match="after the latest transform"):
        tree().lookup("map", "base_footprint", 3.0)


def test_unknown_and_unconnected_frames_are_named():
    tf = tree()
    with pytest.raises(TransformError, match="unknown frame 'camera_link'"):
        tf.lookup("map", "camera_link")
    tf.set("world", "elsewhere", np.eye(4), static=True)
    with pytest.raises(TransformError, match="not connected"):
        tf.lookup("map", "elsewhere")


def test_messages_are_read_like_tf2_msgs():
    def stamped(parent, child, x, sec):
        return NS(
            header=NS(frame_id=parent, stamp=NS(sec=sec, nanosec=0)),
            child_frame_id=child,
            transform=NS(translation=NS(x=x, y=0.0, z=0.0), rotation=NS(x=0.0, y=0.0, z=0.0, w=1.0)),
        )

    tf = TransformBuffer()
    tf.add_message(NS(transforms=[stamped("/odom", "base_footprint", 0.5, 1)]))
    tf.add_message(stamped("base_footprint", "base_link", 0.0, 0), static=True)
    assert pose2d(tf.lookup("odom", "base_link", 1.0))[0] == pytest.approx(0.5)


def test_quaternions_round_trip_and_interpolate_on_the_short_arc():
    q = (0.1, -0.2, 0.3, 0.9)
    n = math.sqrt(sum(c * c for c in q))
    assert matrix_quaternion(quaternion_matrix(*q)) == pytest.approx(tuple(c / n for c in q))
    half = interpolate(planar(0, 0, 0.0), planar(2, 0, 1.0), 0.5)
    assert pose2d(half) == pytest.approx((1.0, 0.0, 0.5))
