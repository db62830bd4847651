"""ROS 2 (rclpy) side of the engine.

    host     RosHost: one rclpy Context, its nodes and one executor thread
    qos      QoS settings by name ("sensor", "latched", a depth)
    client   goals and service calls sent from the executor thread
    server   ``serve(rt)``: /actorbt/call and one action server per tree
    cli      ``actorbt serve``, ``actorbt goal``, ``actorbt rcall``

The ROS transport of the bus is :class:`bt_engine.bus.ros.RosTransport`.

Nothing here imports rclpy until it is used, so ``actorbt`` starts quickly and
builds without ROS still run the local bus. Discovery stays on this machine unless
``ROS_AUTOMATIC_DISCOVERY_RANGE`` says otherwise (see ``host.py``).
"""
from __future__ import annotations

from typing import Any

__all__ = ["RosHost", "Server", "serve"]


def __getattr__(name: str) -> Any:
    if name == "RosHost":
        from .host import RosHost
        return RosHost
    if name in ("Server", "serve"):
        from . import server
        return getattr(server, name)
    raise AttributeError(name)
