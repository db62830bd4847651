"""The tree's status on ``/actorbt/status`` as ``diagnostic_msgs/DiagnosticArray``.

Why DiagnosticArray: it is the standard ROS type for "named things and their state"
(``/diagnostics``), so ``ros2 bag play``, ``ros2 topic echo``, rqt_runtime_monitor and
Foxglove's Diagnostics panels show it without any type of ours; std_msgs/String with
JSON would need a parser in every viewer.

One message per status change of a tree node, in the order the tree reports them:

============  ===============================================================
header.stamp  the runtime clock (the simulator's clock under ``--clock virtual``)
status[0]     ``name``: the node path, prefixed by the tree (``bt_search/search/look``);
              ``message``: the new status, RUNNING, SUCCESS, FAILURE or INVALID;
              ``level``: OK (RUNNING, SUCCESS), ERROR (FAILURE), STALE (INVALID:
              halted or reset); ``hardware_id``: ``actorbt``;
              ``values``: ``tree``, ``path``, ``previous`` (the old status), ``run``
              (the run's number in this process), ``depth`` (0: the top tree),
              ``time`` (the same instant as the stamp, in seconds)
============  ===============================================================

A publisher of these messages is a :class:`~bt_engine.trees.TreeObserver`; it publishes
on the runtime's bus, so the bag recorder and the Foxglove view take it like any topic,
and on the ``ros`` bus ROS tools see it live.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_engine.bus.messages import RosMessage
from bt_engine.trees import TreeObserver

if TYPE_CHECKING:
    from py_trees.common import Status

    from bt_engine.trees import TreeHost, TreeRun

__all__ = ["LEVELS", "STATUS_TOPIC", "TreeStatusPublisher", "status_message"]

STATUS_TOPIC = "/actorbt/status"
#: DiagnosticStatus level of each py_trees status (OK=0, WARN=1, ERROR=2, STALE=3)
LEVELS = {"RUNNING": 0, "SUCCESS": 0, "FAILURE": 2, "INVALID": 3}
#: messages a late ROS subscriber may still miss: this is a stream, not a state
STATUS_DEPTH = 100


def _stamp(t: float) -> RosMessage:
    from builtin_interfaces.msg import Time

    sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
    return Time(sec=sec, nanosec=nsec)


def status_message(tree: str, path: str, old: str, new: str, t: float, *, run: int = 0, depth: int = 0) -> RosMessage:
    """The DiagnosticArray for node ``path`` of ``tree`` going ``old`` -> ``new`` at ``t`` [s]."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

    status = DiagnosticStatus(
        level=bytes([LEVELS.get(new, 1)]), name=f"{tree}/{path}", message=new, hardware_id="actorbt"
    )
    status.values = [
        KeyValue(key=k, value=str(v))
        for k, v in (
            ("tree", tree),
            ("path", path),
            ("previous", old),
            ("run", run),
            ("depth", depth),
            ("time", repr(float(t))),
        )
    ]
    msg = DiagnosticArray(status=[status])
    msg.header.stamp = _stamp(t)
    return msg


class TreeStatusPublisher(TreeObserver):
    """Publishes every status change of the host's tree runs on :data:`STATUS_TOPIC`.

    Add it to ``host.observers`` before the runs to watch start; :meth:`close` removes it.
    """

    def __init__(self, host: TreeHost, topic: str = STATUS_TOPIC) -> None:
        from diagnostic_msgs.msg import DiagnosticArray

        self.host = host
        self.rt = host.rt
        self.topic = topic
        self._pub = self.rt.bus.publisher(topic, DiagnosticArray, STATUS_DEPTH)
        #: messages published, for the curious (and the tests)
        self.published = 0
        host.observers.append(self)

    def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
        self._pub.publish(
            status_message(run.mission.name, path, old.name, new.name, self.rt.now(), run=run.id, depth=run.depth)
        )
        self.published += 1

    def close(self) -> None:
        if self in self.host.observers:
            self.host.observers.remove(self)
