"""navstack's share of tf: the listener (:class:`planning.tf_listener.TfListener`, base
edges only) and the messages the localiser sends (map -> odom as a planar transform)."""

from __future__ import annotations

import math
from typing import Any

from geometry_msgs.msg import TransformStamped

from planning.tf_buffer import TransformError
from planning.tf_listener import BASE_CHILDREN, TF, TF_STATIC, TfListener

__all__ = ["TfListener", "TransformError", "planar_transform", "to_stamp", "BASE_CHILDREN", "TF", "TF_STATIC"]


def to_stamp(t: float, stamp: Any) -> Any:
    """Fill a builtin_interfaces/Time ``stamp`` with ``t`` [s]; returns it."""
    sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
    stamp.sec, stamp.nanosec = int(sec), int(nsec)
    return stamp


def planar_transform(parent: str, child: str, pose, t: float) -> TransformStamped:
    """A TransformStamped of the planar pose (x, y, yaw) of ``child`` in ``parent``."""
    msg = TransformStamped()
    to_stamp(t, msg.header.stamp)
    msg.header.frame_id, msg.child_frame_id = parent, child
    msg.transform.translation.x, msg.transform.translation.y = float(pose[0]), float(pose[1])
    msg.transform.rotation.z = math.sin(pose[2] / 2)
    msg.transform.rotation.w = math.cos(pose[2] / 2)
    return msg
