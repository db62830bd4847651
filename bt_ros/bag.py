"""Recording the robot's topics and the tree to a rosbag2 folder (``--bag DIR``).

The folder is what ``ros2 bag record -s mcap`` writes: ``metadata.yaml`` (version 9) and
one MCAP file (``ros2`` profile, CDR messages, ``ros2msg`` schemas), written with the
``rosbags`` library. ``ros2 bag play``, ``ros2 bag info``, Foxglove and rosbags read it
with no type of ours.

How it taps the topics: it subscribes on the runtime's bus, like any other subscriber.
On the ``local`` bus (the simulator in this process) that is the only way in; on the
``ros`` bus the same subscriptions are rclpy subscriptions. Each message is serialized
by rclpy (:func:`bt_ros.cdr.serialize`: the bytes DDS would carry) and written
with the runtime clock's time of its arrival (the simulator's clock under the virtual
clock; the stamps in the headers are on the same clock). The simulator publishes its
sensors only while someone subscribes: recording makes it publish them all, and render
the camera at its rate.

What is recorded (:data:`DEFAULT_TOPICS`, the topics any ROS mobile robot has): /tf,
/tf_static, /odom, /scan, /joint_states, /map, the tree's status on ``/actorbt/status``
(diagnostic_msgs/DiagnosticArray, see :mod:`bt_ros.tree_status`), and, when a tree run is recorded, its trace on
``/actorbt/trace`` (std_msgs/String, one JSON Lines record per message, the header
first: exactly the lines of ``--record``'s file), which ``actorbt replay`` reads. The
robot's own topics come from actorbt.yaml (``robot: topics:``): for the reference robot
its colour camera, recorded as image_transport's compressed topic
(``/camera/color/image_raw/compressed``, sensor_msgs/CompressedImage, JPEG), and the
camera info.
"""

from __future__ import annotations

import collections
import logging
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Callable, NamedTuple

from bt_engine.bus.messages import RosMessage, message_class
from bt_engine.bus.qos import is_latched
from bt_engine.errors import ActorbtError, RuntimeClosedError
from .cdr import message_definition, serialize, type_hash
from .compressed import JPEG_QUALITY, CompressionError, compress_image, compressed_topic
from .rostypes import QosSetting
from .tree_status import STATUS_TOPIC

if TYPE_CHECKING:
    from rosbags.interfaces import Connection, Qos

    from bt_engine import Runtime
    from bt_engine.bus.transport import Subscription

__all__ = ["BagError", "BagRecorder", "BagTopic", "DEFAULT_TOPICS", "TRACE_TOPIC", "check_bag_path"]

log = logging.getLogger("actorbt.bag")

TRACE_TOPIC = "/actorbt/trace"
STRING = "std_msgs/msg/String"


class BagError(ActorbtError):
    """A bag cannot be written or read: the folder exists, or it is no rosbag2 folder."""


class BagTopic(NamedTuple):
    """One topic to record."""

    #: the topic on the bus
    name: str
    #: its ROS type, ``pkg/msg/Name``
    type: str
    #: the subscription's QoS setting (:mod:`bt_engine.bus.qos`); also what the bag says
    #: the topic offered, so ``ros2 bag play`` latches /map and /tf_static again
    qos: QosSetting = 10
    #: a sensor_msgs/Image recorded as CompressedImage on ``<name>/compressed``
    compress: bool = False

    @property
    def bag_name(self) -> str:
        return compressed_topic(self.name) if self.compress else self.name

    @property
    def bag_type(self) -> str:
        return "sensor_msgs/msg/CompressedImage" if self.compress else self.type


DEFAULT_TOPICS: tuple[BagTopic, ...] = (
    BagTopic("/tf", "tf2_msgs/msg/TFMessage", 100),
    BagTopic("/tf_static", "tf2_msgs/msg/TFMessage", "latched"),
    BagTopic("/odom", "nav_msgs/msg/Odometry", 50),
    BagTopic("/scan", "sensor_msgs/msg/LaserScan", "sensor"),
    BagTopic("/joint_states", "sensor_msgs/msg/JointState", 50),
    BagTopic("/map", "nav_msgs/msg/OccupancyGrid", "latched"),
    BagTopic(STATUS_TOPIC, "diagnostic_msgs/msg/DiagnosticArray", 100),
)


def check_bag_path(path: str | Path) -> Path:
    """``path`` as a folder a new bag may be written to: absent, or an empty folder.

    Raises:
        BagError: it is a file, or a folder with something in it.
    """
    path = Path(path)
    if path.is_dir():
        if any(path.iterdir()):
            raise BagError(
                f"--bag {path}: the folder exists and is not empty; a bag is written "
                "to a new folder (choose another name or remove it)"
            )
    elif path.exists():
        raise BagError(f"--bag {path}: that is a file; a bag is a folder (give a new folder's name)")
    return path


def _offered_qos(qos: QosSetting) -> Qos:
    """The rosbags Qos a publisher with our setting offers (metadata.yaml)."""
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
    from bt_engine.bus.qos import qos_depth

    default = QosTime(0, 0)  # deadline, lifespan, lease: the defaults (none)
    best_effort = isinstance(qos, str) and qos in ("sensor", "sensor_data")
    return Qos(
        history=QosHistory.KEEP_LAST,
        depth=qos_depth(qos),
        reliability=QosReliability.BEST_EFFORT if best_effort else QosReliability.RELIABLE,
        durability=QosDurability.TRANSIENT_LOCAL if is_latched(qos) else QosDurability.VOLATILE,
        deadline=default,
        lifespan=default,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=default,
        avoid_ros_namespace_conventions=False,
    )


class _TraceSink:
    """A text stream for :class:`~bt_engine.trees.TraceRecorder`: each line it is given
    becomes one std_msgs/String on /actorbt/trace."""

    def __init__(self, recorder: BagRecorder) -> None:
        self._recorder = recorder
        self._partial = ""

    def write(self, text: str) -> int:
        from std_msgs.msg import String

        lines = (self._partial + text).split("\n")
        self._partial = lines.pop()
        for line in lines:
            self._recorder.write(TRACE_TOPIC, String(data=line))
        return len(text)

    def flush(self) -> None:
        pass


class BagRecorder:
    """Records :data:`DEFAULT_TOPICS` (or ``topics``) of ``rt``'s bus into a new rosbag2
    folder ``path`` until :meth:`close`.

    ``counts`` holds the messages written per bag topic. :meth:`trace_sink` gives a text
    stream for a :class:`~bt_engine.trees.TraceRecorder` that writes the trace into the
    bag (``/actorbt/trace``).

    Raises:
        BagError: ``path`` exists and is not an empty folder.
    """

    def __init__(
        self,
        rt: Runtime,
        path: str | Path,
        topics: tuple[BagTopic, ...] = DEFAULT_TOPICS,
        *,
        jpeg_quality: int = JPEG_QUALITY,
    ) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.rt = rt
        self.path = check_bag_path(path)
        if self.path.is_dir():
            self.path.rmdir()  # empty: the writer makes the folder itself
        self.topics = tuple(topics)
        self.jpeg_quality = jpeg_quality
        self.counts: collections.Counter[str] = collections.Counter()
        self._lock = threading.Lock()  # trace lines (log records) may come from other threads
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        clock = "virtual" if getattr(rt.clock, "virtual", False) else "wall"
        self._writer.set_custom_data("actorbt.clock", clock)
        self._writer.open()
        self._connections: dict[str, Connection] = {}
        self._subs: list[Subscription] = []
        self._warned: set[str] = set()
        self._closed = False
        try:
            for topic in self.topics:
                self._add_connection(topic.bag_name, topic.bag_type, topic.qos)
            rt.run_on_hub(self._subscribe)
        except BaseException:
            self._unsubscribe()
            self._writer.close()
            raise

    def _add_connection(self, name: str, type_name: str, qos: QosSetting) -> None:
        self._connections[name] = self._writer.add_connection(
            name,
            type_name,
            msgdef=message_definition(type_name),
            rihs01=type_hash(type_name),
            serialization_format="cdr",
            offered_qos_profiles=[_offered_qos(qos)],
        )

    def _subscribe(self) -> None:
        for topic in self.topics:
            self._subs.append(
                self.rt.bus.subscribe(topic.name, message_class(topic.type), self._receiver(topic), topic.qos)
            )

    def _receiver(self, topic: BagTopic) -> Callable[[RosMessage], None]:
        name = topic.bag_name
        if not topic.compress:
            return lambda msg: self.write(name, msg)

        def compress(msg: RosMessage) -> None:
            try:
                self.write(name, compress_image(msg, self.jpeg_quality))
            except CompressionError as exc:
                if name not in self._warned:  # say it once, keep recording the rest
                    self._warned.add(name)
                    log.warning("not recording %s: %s", name, exc)

        return compress

    def trace_sink(self) -> _TraceSink:
        """A text stream whose lines go to ``/actorbt/trace`` (adds that topic)."""
        with self._lock:
            if TRACE_TOPIC not in self._connections:
                self._add_connection(TRACE_TOPIC, STRING, "reliable")
        return _TraceSink(self)

    def write(self, topic: str, msg: RosMessage) -> None:
        """Write ``msg`` on bag topic ``topic`` at the runtime clock's now."""
        data = serialize(msg)
        with self._lock:  # stamped under the lock: the file's order is the order in time
            if self._closed:
                return
            stamp = int(round(self.rt.now() * 1e9))
            self._writer.write(self._connections[topic], stamp, data)
            self.counts[topic] += 1

    def _unsubscribe(self) -> None:
        subs, self._subs = self._subs, []
        for sub in subs:
            sub.close()

    def close(self) -> None:
        """Stop recording and finish the bag (metadata.yaml)."""
        if self._closed:
            return
        try:
            self.rt.run_on_hub(self._unsubscribe)
        except RuntimeClosedError:
            self._unsubscribe()
        with self._lock:
            self._closed = True
            self._writer.close()

    def __enter__(self) -> BagRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
