"""The transport interface behind SubSystem edges. Messages are real ROS 2 classes.

``local`` (in-process, delivered on the hub) is the embedded default; the ROS transport
implements the same interface over rclpy.
"""
from __future__ import annotations

from typing import Any, Callable, Protocol


class Publisher(Protocol):
    topic: str

    def publish(self, msg: Any) -> None: ...


class Subscription(Protocol):
    topic: str

    def close(self) -> None: ...


class Transport:
    """What the runtime needs from a message transport."""

    name = "abstract"

    def publisher(self, topic: str, msg_type: type, qos: int = 10) -> Publisher:
        raise NotImplementedError

    def subscribe(self, topic: str, msg_type: type, callback: Callable[[Any], None],
                  qos: int = 10) -> Subscription:
        """``callback(msg)`` runs on the hub and must not block."""
        raise NotImplementedError

    def subscription_count(self, topic: str) -> int:
        raise NotImplementedError

    def register_action(self, scope: Any, name: str, action_type: type, server: str) -> Any:
        from ..errors import ActorbtError
        raise ActorbtError(f"the {self.name} transport has no action clients; "
                           "use the ros transport (transport: ros in actorbt.yaml)")

    def register_service(self, scope: Any, name: str, srv_type: type, server: str) -> Any:
        from ..errors import ActorbtError
        raise ActorbtError(f"the {self.name} transport has no service clients; "
                           "use the ros transport (transport: ros in actorbt.yaml)")

    def close(self) -> None:
        pass
