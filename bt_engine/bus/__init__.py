"""Message transports, the abstraction only: what SubSystem edges need, and the
in-process bus.

    transport   Transport: the interface the runtime uses (topics, actions, services),
                and what it lists of them (TopicInfo, EndpointInfo)
    local       LocalBus: in-process topics delivered on the hub (the embedded default)
    qos         QoS settings by name and the stream depth each one keeps (pure Python)
    messages    ROS type names, and messages as plain data for people (``topic echo``)

Layering: ``bus`` imports only ``bt_engine.errors`` and knows nothing of ROS. The
rclpy transport, :class:`bt_ros.transport.RosTransport`, lives in the ``ros``
package, which sits above this one.
"""

from .local import LocalBus
from .transport import Transport, close_publishers

__all__ = ["LocalBus", "Transport", "close_publishers"]
