"""What the ROS graph offers, as one node has discovered it: topics, actions, services,
and the QoS that hears a topic's publishers (what ``ros2 topic`` asks the graph).

Each function takes an rclpy node and runs where the caller runs it; the transport runs
them on its executor thread (:meth:`bt_ros.transport.RosTransport.topics`).
Hidden names (a part starting with ``_``, such as an action's ``/_action/`` topics and
services) are left out, as ``ros2 topic list`` leaves them out.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_engine.bus.transport import EndpointInfo, TopicInfo, qos_label

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.qos import QoSProfile
    from rclpy.topic_endpoint_info import TopicEndpointInfo

__all__ = ["action_infos", "hidden", "matching_qos", "service_infos", "topic_infos"]


def hidden(name: str) -> bool:
    """A hidden topic or service: some part of its name starts with ``_``."""
    return any(part.startswith("_") for part in name.split("/"))


def topic_infos(node: Node) -> list[TopicInfo]:
    """Every visible topic of the graph: its type(s), publishers, subscribers and what
    its publishers offer."""
    found = []
    for name, types in sorted(node.get_topic_names_and_types()):
        if hidden(name):
            continue
        pubs = node.get_publishers_info_by_topic(name)
        found.append(TopicInfo(name, ", ".join(types), len(pubs), node.count_subscribers(name), _offered(pubs)))
    return found


def _offered(publishers: list[TopicEndpointInfo]) -> str:
    """The QoS every publisher offers (the weakest reliability and durability)."""
    if not publishers:
        return ""
    labels = [qos_label(p.qos_profile) for p in publishers]
    best_effort = any(label.startswith("best effort") for label in labels)
    latched = all(label.endswith("transient local") for label in labels)
    return ("best effort" if best_effort else "reliable") + (", transient local" if latched else "")


def action_infos(node: Node) -> list[EndpointInfo]:
    """Every action of the graph (with a server or a client)."""
    from rclpy.action import get_action_names_and_types

    return [EndpointInfo(name, ", ".join(types)) for name, types in sorted(get_action_names_and_types(node))]


def service_infos(node: Node) -> list[EndpointInfo]:
    """Every visible service of the graph."""
    return [
        EndpointInfo(name, ", ".join(types))
        for name, types in sorted(node.get_service_names_and_types())
        if not hidden(name)
    ]


def matching_qos(node: Node, topic: str, depth: int = 10) -> QoSProfile:
    """A subscription QoS that hears every publisher of ``topic`` (as ``ros2 topic echo``
    chooses it): best effort if any publisher is, transient local (a latched topic's last
    message too) if all publishers are; reliable and volatile otherwise. With no publisher
    yet, best effort and volatile, which hears any publisher that comes but a latched one's
    past message."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    offered = _offered(node.get_publishers_info_by_topic(topic)) or "best effort"
    return QoSProfile(
        depth=depth,
        reliability=(
            ReliabilityPolicy.BEST_EFFORT if offered.startswith("best effort") else ReliabilityPolicy.RELIABLE
        ),
        durability=(
            DurabilityPolicy.TRANSIENT_LOCAL if offered.endswith("transient local") else DurabilityPolicy.VOLATILE
        ),
    )
