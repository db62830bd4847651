"""The transport interface behind SubSystem edges. Messages are real ROS 2 classes.

``local`` (:mod:`bt_engine.bus.local`, in-process, delivered on the hub) is the embedded
default; :mod:`bt_engine.ros.transport` implements the same interface over rclpy.
``qos`` is a depth or a name of :mod:`bt_engine.bus.qos`.
"""
from __future__ import annotations

from typing import Any, Callable, Protocol

from ..errors import ActorbtError


class Publisher(Protocol):
    topic: str

    def publish(self, msg: Any) -> None: ...


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

    def subscribe(self, topic: str, msg_type: type, callback: Callable[[Any], None],
                  qos: Any = 10) -> Subscription:
        """``callback(msg)`` runs on the hub and must not block."""
        raise NotImplementedError

    def subscription_count(self, topic: str) -> int:
        raise NotImplementedError

    def register_action(self, scope: Any, name: str, action_type: type, server: str) -> Any:
        raise ActorbtError(f"the {self.name} transport has no action clients; "
                           "use the ros transport (transport: ros in actorbt.yaml)")

    def action_server(self, name: str, action_type: type, on_goal: Callable[[Any], None]) -> Any:
        """Serve action ``name``: ``on_goal(goal)`` runs on the hub with each goal's
        :class:`~bt_engine.bus.actions.ServerGoal`. Returns a handle with ``close()``."""
        raise ActorbtError(f"the {self.name} transport cannot serve actions")

    def register_service(self, scope: Any, name: str, srv_type: type, server: str) -> Any:
        raise ActorbtError(f"the {self.name} transport has no service clients; "
                           "use the ros transport (transport: ros in actorbt.yaml)")

    def close(self) -> None:
        pass
