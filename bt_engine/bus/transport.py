"""The transport interface behind SubSystem edges. Messages are real ROS 2 classes.

``local`` (:mod:`bt_engine.bus.local`, in-process, delivered on the hub) is the embedded
default; :mod:`bt_ros.transport` implements the same interface over rclpy.
``qos`` is a depth or a name of :mod:`bt_engine.bus.qos`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, NamedTuple, Protocol

from ..errors import ActorbtError
from .messages import RosAction
from .qos import is_latched

if TYPE_CHECKING:
    from ..actor import ActorRef
    from .actions import OnGoal


class TopicInfo(NamedTuple):
    """One topic as a transport sees it (``transport.topics()``)."""

    name: str
    #: the ROS type name, e.g. ``sensor_msgs/msg/LaserScan``
    type: str
    publishers: int
    subscribers: int
    #: what the publishers offer, when the transport knows: ``reliable``, ``best effort``,
    #: with ``, transient local`` for a latched topic; ``""`` when unknown
    qos: str = ""


class EndpointInfo(NamedTuple):
    """An action or service (``transport.actions()``, ``transport.services()``)."""

    name: str
    #: the ROS type name, e.g. ``control_msgs/action/FollowJointTrajectory``
    type: str


def qos_label(qos: Any) -> str:
    """What a QoS setting (see :mod:`bt_engine.bus.qos`) offers: ``reliable`` or ``best
    effort``, with ``, transient local`` for a latched one."""
    if isinstance(qos, str):
        if qos in ("sensor", "sensor_data"):
            return "best effort"
        return "reliable, transient local" if is_latched(qos) else "reliable"
    if isinstance(qos, int) or qos is None:
        return "reliable"
    # an rclpy QoSProfile: read its policies by name (no rclpy import here)
    reliability = getattr(getattr(qos, "reliability", None), "name", "RELIABLE")
    text = "best effort" if reliability == "BEST_EFFORT" else "reliable"
    return text + (", transient local" if is_latched(qos) else "")


class Publisher(Protocol):
    topic: str

    def publish(self, msg: Any) -> None: ...


def close_publishers(*publishers: Any) -> None:
    """Take publishers off the bus (a node that stops): each that can be closed is."""
    for pub in publishers:
        close = getattr(pub, "close", None)
        if close is not None:
            close()


class Subscription(Protocol):
    topic: str

    def close(self) -> None: ...


class Transport:
    """What the runtime needs from a message transport."""

    name = "abstract"
    #: True when subscription callbacks come only from code running on the hub (the
    #: local bus): subscriber actors are then ``hub_only`` and the virtual clock may
    #: jump while they wait. A transport fed by other threads (ROS) leaves it False.
    delivers_on_hub = False

    def publisher(self, topic: str, msg_type: type, qos: Any = 10) -> Publisher:
        raise NotImplementedError

    def subscribe(self, topic: str, msg_type: type, callback: Callable[[Any], None], qos: Any = 10) -> Subscription:
        """``callback(msg)`` runs on the hub and must not block."""
        raise NotImplementedError

    def subscription_count(self, topic: str) -> int:
        raise NotImplementedError

    def publisher_count(self, topic: str) -> int | None:
        """Publishers of ``topic`` (None when the transport cannot tell). Safe on the hub."""
        return None

    def silence_hint(self, publishers: int) -> str:
        """Why a topic with ``publishers`` publishers may have sent nothing (the end of
        a subscriber's ActorTimeout)."""
        if publishers == 0:
            return "is the robot or the simulator running?"
        return "does it publish that seldom?"

    def register_action(self, scope: Any, name: str, action_type: type[RosAction], server: str) -> ActorRef:
        raise ActorbtError(
            f"the {self.name} transport has no action clients; use the ros transport (transport: ros in actorbt.yaml)"
        )

    def action_server(self, name: str, action_type: type[RosAction], on_goal: OnGoal) -> Any:
        """Serve action ``name``: ``on_goal(goal)`` runs on the hub with each goal's
        :class:`~bt_engine.bus.actions.ServerGoal`. Returns a handle with ``close()``."""
        raise ActorbtError(f"the {self.name} transport cannot serve actions")

    def register_service(self, scope: Any, name: str, srv_type: type, server: str) -> ActorRef:
        raise ActorbtError(
            f"the {self.name} transport has no service clients; use the ros transport (transport: ros in actorbt.yaml)"
        )

    def topics(self) -> list[TopicInfo]:
        """Every topic the transport knows of, by name: with a publisher or a subscriber
        in this process (local), or anywhere in the discovered graph (ROS)."""
        raise ActorbtError(f"the {self.name} transport cannot list its topics")

    def actions(self) -> list[EndpointInfo]:
        """The actions served, by name (on the ROS transport: those discovered)."""
        return []

    def services(self) -> list[EndpointInfo]:
        """The services served, by name (on the ROS transport: those discovered)."""
        return []

    def close(self) -> None:
        pass


def silence(bus: Transport, topic: str, msg_type: type, seconds: float) -> str:
    """What a subscriber that waited ``seconds`` for a message on ``topic`` in vain says:
    the topic, its type, and whether anything publishes it."""
    from .messages import type_name

    what = f"no message on {topic} ({type_name(msg_type)}) within {seconds:g} s"
    try:
        n = bus.publisher_count(topic)
    except Exception:  # a closed transport: say what is known
        n = None
    if n is None:
        return what
    if n == 0:
        return f"{what}: nothing publishes it ({bus.silence_hint(0)})"
    return f"{what}, though {n} publisher{'s' if n > 1 else ''} {'have' if n > 1 else 'has'} it ({bus.silence_hint(n)})"
