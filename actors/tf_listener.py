"""The robot's transform tree for the actors, as tf2_ros's Buffer + TransformListener give
it to a node: one :class:`planning.tf_listener.TfListener` per runtime, shared by the
navigation and the camera.

Frames (REP 105): map -> odom (the localiser: AMCL, or navstack's stand-in) -> base_footprint
(the odometry) -> base_link -> camera_link -> camera_optical_frame, base_scan, the arm's
links. Only the base's dynamic edges are kept; the arm's joints also go out on /tf 30
times a second and would only cost time here.
"""

from __future__ import annotations

from typing import Any

from planning.tf_buffer import TransformError
from planning.tf_listener import TfListener

__all__ = ["TfListener", "TransformError", "tf_listener", "MAP", "ODOM", "BASE"]

MAP, ODOM, BASE = "map", "odom", "base_footprint"


def tf_listener(subsystem: Any) -> TfListener:
    """The runtime's listener (made on first use), for any of its subsystems."""
    rt = subsystem.runtime
    return rt.extension("actors.tf_listener", lambda: TfListener(rt.bus, (ODOM, BASE)))
