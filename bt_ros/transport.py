"""The ROS 2 transport: the bus interface (:class:`bt_engine.bus.Transport`) over rclpy
and Fast DDS.

``Runtime(bus=RosTransport)`` (``transport: ros`` in actorbt.yaml, or ``--bus ros``) keeps
the actor-facing API of the local bus: ``register_publisher`` / ``register_subscriber``
make the same actors, and ``register_action`` / ``register_service`` make async actors
that send goals and requests to servers in this or other processes.

Threads: one private rclpy Context per transport, one node, one executor thread
(:class:`bt_ros.host.RosHost`). Message callbacks hand over to the hub with
``call_soon_threadsafe``; goals are sent from the executor thread.

Everything here completes from the executor thread, so under the virtual clock a goal,
a request or a subscriber waiting for a message keeps virtual time at wall pace (the
rule of :class:`bt_engine.clock.VirtualClock`): a deadline never overtakes a reply.
"""

from __future__ import annotations

import logging
import os
from typing import TYPE_CHECKING, Callable, TypeVar

from bt_engine.bus.messages import RosAction, RosMessage, RosService
from bt_engine.bus.transport import EndpointInfo, TopicInfo, Transport
from bt_engine.modes import Kind
from bt_engine.bus.actions import ServerGoal, build_message, message_doc, message_signature, public_name
from .client import GoalCall, ServerWait, ServiceCall
from .host import RosClosedError, RosHost
from .qos import qos_profile
from .rostypes import QosSetting, Value

if TYPE_CHECKING:
    from rclpy.action import ActionClient
    from rclpy.client import Client
    from rclpy.node import Node
    from rclpy.publisher import Publisher
    from rclpy.qos import QoSProfile
    from rclpy.subscription import Subscription

    from bt_engine.actor import ActorRef
    from bt_engine.handles import Done
    from bt_engine.runtime import Runtime
    from bt_engine.subsystem import SubSystem
    from .action_server import RosActionServer

log = logging.getLogger("actorbt.ros")

#: a publisher or a subscription (what _destroy_later destroys)
_Endpoint = TypeVar("_Endpoint")

#: why a topic's publisher may not be found (in a subscriber's ActorTimeout)
DISCOVERY_RANGE_HINT = "ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE must match on both sides"

__all__ = ["RosPublisher", "RosSubscription", "RosTransport"]


class RosPublisher:
    """``publish(msg)`` on a ROS topic; safe from any thread. ``close()`` takes it off
    the graph."""

    __slots__ = ("topic", "_pub", "_host", "_node")

    def __init__(self, host: RosHost, pub: Publisher, topic: str, node: Node | None = None) -> None:
        self.topic = topic
        self._pub: Publisher | None = pub
        self._host = host
        self._node = node

    def publish(self, msg: RosMessage) -> None:
        if self._host.closed:
            raise RosClosedError(f"cannot publish on {self.topic}: the ROS transport is closed")
        if self._pub is None:
            raise RosClosedError(f"cannot publish on {self.topic}: the publisher is closed")
        self._pub.publish(msg)

    def close(self) -> None:
        pub, self._pub = self._pub, None
        if pub is not None and self._node is not None and not self._host.closed:
            _destroy_later(self._host, self._node.destroy_publisher, pub, self.topic)


class RosSubscription:
    """A ROS subscription whose messages are delivered on the hub; ``close()`` ends it."""

    __slots__ = ("topic", "callback", "closed", "_sub", "_transport")

    def __init__(self, transport: "RosTransport", topic: str, callback: Callable[[RosMessage], None]) -> None:
        self.topic = topic
        self.callback = callback
        self.closed = False
        self._sub: Subscription | None = None
        self._transport = transport

    def _on_message(self, msg: RosMessage) -> None:  # executor thread
        if not self.closed:
            self._transport._rt.call_soon_threadsafe(self._receive, msg)

    def _receive(self, msg: RosMessage) -> None:  # hub
        if not self.closed:
            self.callback(msg)

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self._transport._subs.discard(self)
        t = self._transport
        if not t.host.closed and self._sub is not None:
            _destroy_later(t.host, t.node.destroy_subscription, self._sub, self.topic)


def _destroy_later(host: RosHost, destroy: Callable[[_Endpoint], bool], entity: _Endpoint, topic: str) -> None:
    """Destroy a publisher or subscription on the executor thread: destroyed from another
    thread while the executor waits on it, rclpy fails in the executor ("cannot use
    Destroyable because destruction was requested")."""

    def run() -> None:
        try:
            destroy(entity)
        except Exception:
            log.exception("destroying an endpoint of %s failed", topic)

    try:
        host.post(run)
    except RosClosedError:
        pass  # the node goes with the host


class RosTransport(Transport):
    """Topics, actions and services over rclpy.

    Args:
        rt: the runtime whose hub receives callbacks.
        node_name: the node's name (default ``actorbt_<pid>_<host id>``).
        server_timeout: how long an action or service actor waits for its server to be
            discovered [s, wall] before failing with ServerUnavailableError.
    """

    name = "ros"

    def __init__(self, rt: "Runtime", node_name: str | None = None, *, server_timeout: float = 10.0) -> None:
        self._rt = rt
        self.server_timeout = server_timeout
        self.host = RosHost("bus")
        try:
            self.node = self.host.create_node(node_name or f"actorbt_{os.getpid()}_{self.host.id}")
        except BaseException:
            self.host.close()
            raise
        self._waiter = ServerWait(self.node)
        self._subs: set[RosSubscription] = set()
        self._servers: list[RosActionServer] = []
        self._closed = False

    # -- topics --------------------------------------------------------------------------
    def publisher(self, topic: str, msg_type: type, qos: QosSetting = 10) -> RosPublisher:
        pub = self.node.create_publisher(msg_type, topic, qos_profile(qos))
        return RosPublisher(self.host, pub, topic, self.node)

    def subscribe(
        self, topic: str, msg_type: type, callback: Callable[[RosMessage], None], qos: QosSetting = 10
    ) -> RosSubscription:
        """``callback(msg)`` runs on the hub, in arrival order."""
        sub = RosSubscription(self, topic, callback)
        sub._sub = self.node.create_subscription(msg_type, topic, sub._on_message, qos_profile(qos))
        self._subs.add(sub)
        return sub

    def subscription_count(self, topic: str) -> int:
        """Subscriptions to ``topic`` in the ROS graph (every process, this one included)."""
        if self.host.closed:
            return 0
        return self.node.count_subscribers(topic)

    def publisher_count(self, topic: str) -> int | None:
        """Publishers of ``topic`` discovered in the ROS graph (this process included);
        None once the transport is closed."""
        if self.host.closed:
            return None
        return self.node.count_publishers(topic)

    def silence_hint(self, publishers: int) -> str:
        if publishers == 0:
            return f"is the robot or the simulator running? {DISCOVERY_RANGE_HINT}"
        return (
            "does it publish that seldom, or do its QoS and the subscriber's not match? "
            "`actorbt topic list --json --bus ros` shows what it offers"
        )

    # -- the graph (not from the hub: these wait for the executor thread) ----------------
    def topics(self) -> list[TopicInfo]:
        """Every visible topic this node has discovered, in every process (see
        :mod:`bt_ros.graph`); discovery takes a moment after the node starts."""
        from .graph import topic_infos

        return self.host.call(topic_infos, self.node)

    def actions(self) -> list[EndpointInfo]:
        """Every action discovered (served or called anywhere in the graph)."""
        from .graph import action_infos

        return self.host.call(action_infos, self.node)

    def services(self) -> list[EndpointInfo]:
        """Every visible service discovered."""
        from .graph import service_infos

        return self.host.call(service_infos, self.node)

    def matching_qos(self, topic: str) -> QoSProfile:
        """A subscription QoS that hears every publisher of ``topic`` now (best effort if
        any publisher is, transient local if all are), as ``ros2 topic echo`` picks it."""
        from .graph import matching_qos

        return self.host.call(matching_qos, self.node, topic)

    # -- actions and services ----------------------------------------------------------
    def register_action(self, scope: SubSystem, name: str, action_type: type[RosAction], server: str) -> ActorRef:
        """Make async actor ``name(goal=None, **fields)`` sending goals to ``server``.

        ``goal`` is an ``action_type.Goal`` or a mapping of its fields; keyword fields
        override. The result is the ``action_type.Result`` of a succeeded goal; an
        aborted or canceled goal fails with ActionGoalError, a rejected one with
        GoalRejectedError. Cancelling the transaction cancels the goal.
        """
        from rclpy.action import ActionClient

        # Created here, not through host.call: the hub never waits for the executor
        # thread (which may be waiting for the hub), see RosHost.
        client = ActionClient(self.node, action_type, server)
        doc = message_doc(
            f"Send a {public_name(action_type)} goal to action {server} and return its result.",
            "goal",
            action_type.Goal,
        )
        return self._client_actor(scope, name, GoalCall, client, server, action_type.Goal, "goal", doc)

    def action_server(
        self, name: str, action_type: type[RosAction], on_goal: Callable[[ServerGoal], None]
    ) -> RosActionServer:
        """Serve action ``name`` from this node; ``on_goal(goal)`` runs on the hub with a
        :class:`~bt_engine.bus.actions.ServerGoal` (see :mod:`bt_ros.action_server`)."""
        from .action_server import RosActionServer

        server = RosActionServer(self, name, action_type, on_goal)
        self._servers.append(server)
        return server

    @property
    def rt(self) -> "Runtime":
        return self._rt

    def register_service(self, scope: SubSystem, name: str, srv_type: type[RosService], server: str) -> ActorRef:
        """Make async actor ``name(request=None, **fields)`` calling service ``server``;
        the result is the response. Cancelling drops the pending request."""
        client = self.node.create_client(srv_type, server)
        doc = message_doc(
            f"Call service {server} ({public_name(srv_type)}) and return the response.", "request", srv_type.Request
        )
        return self._client_actor(scope, name, ServiceCall, client, server, srv_type.Request, "request", doc)

    def _client_actor(
        self,
        scope: SubSystem,
        name: str,
        call_type: Callable[..., GoalCall | ServiceCall],
        client: ActionClient | Client,
        server: str,
        msg_type: type[RosMessage],
        param: str,
        doc: str,
    ) -> ActorRef:
        """An async actor ``name(<param>=None, **fields)`` that sends one message through
        ``client`` as a ``call_type`` (GoalCall or ServiceCall) from the executor thread."""
        host, waiter = self.host, self._waiter

        def send(done: Done, *args: object, **fields: Value) -> Callable[[], None]:
            # the signature is (<param>=None, **fields), checked by the runtime
            message = args[0] if args else fields.pop(param, None)
            call = call_type(
                client,
                server,
                waiter,
                build_message(msg_type, message, fields),
                server_timeout=self.server_timeout,
                on_result=done,
                on_error=done.fail,
            )
            host.post(call.start)
            return lambda: self._post_quietly(call.cancel)

        return scope.add_actor(name, send, Kind.ASYNC, doc=doc, signature=message_signature(param, msg_type))

    def _post_quietly(self, fn: Callable[[], object]) -> None:
        try:
            self.host.post(fn)
        except RosClosedError:
            pass

    # -- lifecycle -----------------------------------------------------------------------
    def close(self) -> None:
        """Destroy the node, stop the executor thread, shut the context down."""
        if self._closed:
            return
        self._closed = True
        for sub in list(self._subs):
            sub.closed = True
        self._subs.clear()
        for server in self._servers:
            server.close()
        self.host.close()
