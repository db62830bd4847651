"""Names for the values the ROS side passes on without knowing their type.

rosidl generates message classes without type stubs, and an actor may take or return
anything, so these values stay ``Any`` for the type checker; the alias says what the
value is. Messages are :class:`bt_engine.bus.messages.RosMessage` (fields as attributes).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypeAlias, Union

if TYPE_CHECKING:
    from rclpy.qos import QoSProfile

__all__ = ["Json", "Outcome", "QosSetting", "Value"]

#: any value an actor takes or returns, a goal's input or a result (YAML text on the wire)
Value: TypeAlias = Any
#: a JSON value (a document's parts: a tool's JSON Schema)
Json: TypeAlias = Any
#: what a transaction ends with: the actor's result (any value) or a bt_engine Failure
Outcome: TypeAlias = Any
#: a QoS setting of :mod:`bt_engine.bus.qos`: a depth, a name, or an rclpy QoSProfile
QosSetting: TypeAlias = Union[int, str, "QoSProfile", None]
