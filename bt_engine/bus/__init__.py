"""Message transports: the in-process ``local`` bus, and ROS 2 (rclpy)."""
from .local import LocalBus
from .transport import Transport

__all__ = ["LocalBus", "Transport"]
