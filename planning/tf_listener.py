"""tf2_ros's TransformListener: ``/tf`` and ``/tf_static`` from a bus into a
:class:`planning.tf_buffer.TransformBuffer`.

``bus`` is anything with ``subscribe(topic, type, callback, qos)`` (actorbt's transports);
this module subscribes, the buffer stays plain. The simulator (robot_state_publisher and
the base driver on a robot) sends odom -> base_footprint and every joint of the arm on
``/tf`` at the odometry rate; most listeners only need the base's edges, so only the
dynamic edges whose child is in ``children`` are kept (every static edge is): parsing the
arm's joints 30 times a second would cost more than all the rest.
"""

from __future__ import annotations

from typing import Any, Callable, Iterable

from tf2_msgs.msg import TFMessage

from .tf_buffer import TransformBuffer, pose2d

__all__ = ["TfListener", "BASE_CHILDREN", "TF", "TF_STATIC"]

TF, TF_STATIC = "/tf", "/tf_static"
#: the dynamic edges a mobile base's software needs: map -> odom (the localiser), odom ->
#: base_footprint (the odometry)
BASE_CHILDREN = ("odom", "base_footprint")


class TfListener:
    """A transform buffer kept up to date from ``/tf`` and ``/tf_static`` on ``bus``.

    Args:
        bus: the runtime's transport
        children: keep only the dynamic edges whose child frame is one of these (None:
            all of them); static edges are always kept
        on_tf: called with each /tf message, after the buffer has it
    """

    def __init__(
        self, bus: Any, children: Iterable[str] | None = BASE_CHILDREN, on_tf: Callable[[Any], None] | None = None
    ) -> None:
        self.buffer = TransformBuffer()
        self._keep = None if children is None else frozenset(children)
        self._on_tf_cb = on_tf
        self._subs = [
            bus.subscribe(TF, TFMessage, self._on_tf, 100),
            bus.subscribe(TF_STATIC, TFMessage, self._on_static, "latched"),
        ]

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

    def lookup(self, target: str, source: str, t: float | None = None):
        """The 4 x 4 transform from ``source`` to ``target`` at ``t`` (None: the latest);
        raises TransformError when the buffer cannot tell."""
        return self.buffer.lookup(target, source, t)

    def pose(self, target: str, source: str, t: float | None = None) -> tuple[float, float, float]:
        """(x, y, yaw) of frame ``source`` in ``target`` at ``t`` (None: the latest)."""
        return pose2d(self.buffer.lookup(target, source, t))
