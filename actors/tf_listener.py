"""The robot's transform tree for the actors, as tf2_ros's Buffer + TransformListener give
it to a node: ``/tf`` and ``/tf_static`` into a :class:`planning.tf_buffer.TransformBuffer`,
one per runtime, shared by the navigation and the camera.

Frames (REP 105): map -> odom (the localiser: AMCL, or navstack's stand-in) -> base_footprint
(the odometry) -> base_link -> camera_link -> camera_optical_frame, base_scan, the arm's
links. Only the dynamic edges the actors look up are kept (``KEEP``: the base's); the arm's
joints also go out on /tf 30 times a second and would only cost time here.
"""
from __future__ import annotations

from typing import Any

from tf2_msgs.msg import TFMessage

from planning.tf_buffer import TransformBuffer, TransformError, pose2d

__all__ = ["TfListener", "TransformError", "tf_listener", "MAP", "ODOM", "BASE"]

MAP, ODOM, BASE = "map", "odom", "base_footprint"
#: the dynamic edges kept, by child frame
KEEP = frozenset({ODOM, BASE})


class TfListener:
    """/tf and /tf_static on ``bus`` into :attr:`buffer`."""

    def __init__(self, bus: Any, keep: frozenset | None = KEEP) -> None:
        self.buffer = TransformBuffer()
        self._keep = keep
        self._subs = [bus.subscribe("/tf", TFMessage, self._on_tf, 100),
                      bus.subscribe("/tf_static", TFMessage, self._on_static, "latched")]

    def close(self) -> None:
        for s in self._subs:
            s.close()
        self._subs = []

    def _on_tf(self, msg: TFMessage) -> None:
        keep = self._keep
        for ts in msg.transforms:
            if keep is None or ts.child_frame_id in keep:
                self.buffer.add_message(ts)

    def _on_static(self, msg: TFMessage) -> None:
        self.buffer.add_message(msg, static=True)

    def lookup(self, target: str, source: str, t: float | None = None):
        """The 4 x 4 transform from ``source`` to ``target`` at ``t`` (None: the latest)."""
        return self.buffer.lookup(target, source, t)

    def pose(self, target: str = MAP, source: str = BASE, t: float | None = None) -> tuple[float, float, float]:
        """(x, y, yaw) of ``source`` in ``target``."""
        return pose2d(self.buffer.lookup(target, source, t))


def tf_listener(subsystem: Any) -> TfListener:
    """The runtime's listener (made on first use), for any of its subsystems."""
    rt = subsystem.runtime
    return rt.extension("actors.tf_listener", lambda: TfListener(rt.bus))
