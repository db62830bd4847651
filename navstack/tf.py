"""tf2_ros's TransformListener for navstack: ``/tf`` and ``/tf_static`` into a
:class:`planning.tf_buffer.TransformBuffer`, and map -> odom out on ``/tf``.

The simulator (or robot_state_publisher and the base driver on a robot) sends
odom -> base_footprint and every joint of the arm on ``/tf`` at the odometry rate; the
localiser and the navigator only need the base's edges, so :class:`TfListener` keeps the
dynamic edges whose child is in ``children`` (every static edge is kept): parsing the arm's
joints 30 times a second would cost more than all the rest.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Iterable

from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage

from planning.tf_buffer import TransformBuffer, TransformError, pose2d

__all__ = ["TfListener", "TransformError", "planar_transform", "to_stamp"]

TF, TF_STATIC = "/tf", "/tf_static"
#: the dynamic edges the base's software needs: map -> odom (the localiser), odom ->
#: base_footprint (the odometry)
BASE_CHILDREN = ("odom", "base_footprint")


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


class TfListener:
    """A transform buffer kept up to date from ``/tf`` and ``/tf_static`` on ``bus``.

    Args:
        bus: the runtime's transport
        children: keep only the dynamic edges whose child frame is one of these (None:
            all of them); static edges are always kept
        on_tf: called with each /tf message, after the buffer has it
    """

    def __init__(self, bus: Any, children: Iterable[str] | None = BASE_CHILDREN,
                 on_tf: Callable[[Any], None] | None = None) -> None:
        self.buffer = TransformBuffer()
        self._keep = None if children is None else frozenset(children)
        self._on_tf_cb = on_tf
        self._subs = [bus.subscribe(TF, TFMessage, self._on_tf, 100),
                      bus.subscribe(TF_STATIC, TFMessage, self._on_static, "latched")]

    def close(self) -> None:
        for s in self._subs:
            s.close()
        self._subs = []

    def _on_tf(self, msg: TFMessage) -> None:
        keep = self._keep
        for ts in msg.transforms:
            if keep is None or ts.child_frame_id in keep:
                self.buffer.add_message(ts)
        if self._on_tf_cb is not None:
            self._on_tf_cb(msg)

    def _on_static(self, msg: TFMessage) -> None:
        self.buffer.add_message(msg, static=True)

    def pose(self, target: str, source: str, t: float | None = None) -> tuple[float, float, float]:
        """(x, y, yaw) of frame ``source`` in ``target`` at ``t`` (None: the latest);
        raises TransformError when the buffer cannot tell."""
        return pose2d(self.buffer.lookup(target, source, t))
