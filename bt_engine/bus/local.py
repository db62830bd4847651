"""In-process bus: publish/subscribe between actors and the simulator on the hub.

Delivery is deferred to the hub's ready queue in publish order, so a publisher never
runs subscriber code inside its own call, and a run is deterministic.

Durability as in DDS: a topic whose publisher is latched (transient local) keeps its last
message, and a latched subscriber that comes later receives it at once (a map, the
localiser's pose); a volatile subscriber only gets what is published after it subscribed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from ..errors import ActorbtError
from .actions import LocalActionServer, OnGoal, local_client_actor
from .messages import RosAction, type_name
from .qos import is_latched
from .transport import EndpointInfo, TopicInfo, Transport, qos_label

if TYPE_CHECKING:
    from ..actor import ActorRef
    from ..hub import Hub


class TopicTypeError(ActorbtError, TypeError):
    """A topic was used with two different message types."""


class _Topic:
    __slots__ = ("name", "msg_type", "subs", "publishers", "qos", "last")

    def __init__(self, name: str, msg_type: type) -> None:
        self.name = name
        self.msg_type = msg_type
        self.subs: list[LocalSubscription] = []
        #: its live publishers (made, not closed)
        self.publishers = 0
        #: the QoS setting of its first publisher (what a ROS robot would offer)
        self.qos: Any = None
        #: the last message, kept when that publisher is latched
        self.last: Any = None


class LocalPublisher:
    __slots__ = ("topic", "_t", "_bus", "closed")

    def __init__(self, bus: "LocalBus", t: _Topic) -> None:
        self.topic = t.name
        self._t = t
        self._bus = bus
        self.closed = False

    def close(self) -> None:
        """No longer a publisher of the topic (its count drops)."""
        if not self.closed:
            self.closed = True
            self._t.publishers -= 1

    def publish(self, msg: Any) -> None:
        """Deliver ``msg`` to every current subscriber. Safe from any thread."""
        if not isinstance(msg, self._t.msg_type):
            raise TopicTypeError(f"{self.topic} carries {self._t.msg_type.__name__}, not {type(msg).__name__}")
        self._bus._deliver(self._t, msg)


class LocalSubscription:
    __slots__ = ("topic", "callback", "_t", "closed")

    def __init__(self, t: _Topic, callback: Callable[[Any], None]) -> None:
        self.topic = t.name
        self._t = t
        self.callback = callback
        self.closed = False

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            try:
                self._t.subs.remove(self)
            except ValueError:
                pass

    def _receive(self, msg: Any) -> None:
        if not self.closed:
            self.callback(msg)


class LocalBus(Transport):
    """Topics in one process, delivered on the hub."""

    name = "local"
    #: Publishing from another thread is possible but the virtual clock does not wait
    #: for it (such a driver belongs in an async or stream actor, or on the wall clock).
    delivers_on_hub = True

    def __init__(self, hub: "Hub") -> None:
        self._hub = hub
        self._topics: dict[str, _Topic] = {}
        self._actions: dict[str, LocalActionServer] = {}

    def _topic(self, name: str, msg_type: type) -> _Topic:
        t = self._topics.get(name)
        if t is None:
            t = self._topics[name] = _Topic(name, msg_type)
        elif t.msg_type is not msg_type:
            raise TopicTypeError(
                f"topic {name} already carries {t.msg_type.__module__}."
                f"{t.msg_type.__name__}; cannot use it for {msg_type.__name__}"
            )
        return t

    def publisher(self, topic: str, msg_type: type, qos: Any = 10) -> LocalPublisher:
        t = self._topic(topic, msg_type)
        if not t.publishers:
            t.qos = qos
        t.publishers += 1
        return LocalPublisher(self, t)

    def subscribe(
        self, topic: str, msg_type: type, callback: Callable[[Any], None], qos: Any = 10
    ) -> LocalSubscription:
        t = self._topic(topic, msg_type)
        sub = LocalSubscription(t, callback)
        t.subs.append(sub)
        if t.last is not None and is_latched(qos):
            self._post(sub._receive, t.last)
        return sub

    def subscription_count(self, topic: str) -> int:
        t = self._topics.get(topic)
        return len(t.subs) if t is not None else 0

    def publisher_count(self, topic: str) -> int:
        """Live publishers of ``topic`` in this process."""
        t = self._topics.get(topic)
        return t.publishers if t is not None else 0

    def topics(self) -> list[TopicInfo]:
        """Every topic used in this process: its type, publishers made, live subscribers,
        and the QoS its first publisher asked for (the local bus delivers every message
        alike; a ROS robot would offer that QoS)."""
        return [
            TopicInfo(
                t.name, type_name(t.msg_type), t.publishers, len(t.subs), qos_label(t.qos) if t.publishers else ""
            )
            for t in sorted(self._topics.values(), key=lambda t: t.name)
        ]

    def actions(self) -> list[EndpointInfo]:
        """The actions served on this bus."""
        return [EndpointInfo(name, type_name(server.action_type)) for name, server in sorted(self._actions.items())]

    def action_server(self, name: str, action_type: type[RosAction], on_goal: OnGoal) -> LocalActionServer:
        """Serve action ``name`` in this process (one server per name)."""
        current = self._actions.get(name)
        if current is not None:
            raise ActorbtError(f"action {name} is already served on the local bus")
        server = self._actions[name] = LocalActionServer(self._actions, name, action_type, on_goal)
        return server

    def register_action(self, scope: Any, name: str, action_type: type[RosAction], server: str) -> ActorRef:
        """Async actor ``name(goal=None, **fields)`` sending goals to local action ``server``
        (served by ``action_server`` in this process by the time a goal is sent)."""
        return local_client_actor(scope, name, action_type, server, self._actions)

    def _post(self, fn: Callable[[Any], None], msg: Any) -> None:
        hub = self._hub
        (hub.call_soon if hub.in_hub_thread() else hub.call_soon_threadsafe)(fn, msg)

    def _deliver(self, t: _Topic, msg: Any) -> None:
        if is_latched(t.qos):
            t.last = msg
        for sub in list(t.subs):
            self._post(sub._receive, msg)
