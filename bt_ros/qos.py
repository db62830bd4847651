"""rclpy QoS profiles for the named settings of :mod:`bt_engine.bus.qos`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_engine.bus.qos import qos_depth
from .rostypes import QosSetting

if TYPE_CHECKING:
    from rclpy.qos import QoSProfile

__all__ = ["qos_profile"]


def qos_profile(qos: QosSetting) -> QoSProfile:
    """The rclpy QoSProfile for a setting (see :mod:`bt_engine.bus.qos`)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

    if isinstance(qos, QoSProfile):
        return qos
    qos_depth(qos)  # validates
    if isinstance(qos, int):
        return QoSProfile(depth=max(1, qos))
    if qos in ("sensor", "sensor_data"):
        return qos_profile_sensor_data
    if qos in ("latched", "transient_local"):
        return QoSProfile(
            depth=1,
            history=HistoryPolicy.KEEP_LAST,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
    return QoSProfile(depth=10)
