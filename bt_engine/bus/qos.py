"""QoS settings by name, for publishers and subscribers on any transport.

``qos`` may be:

- an int N: reliable, volatile, keep the last N (the local bus's meaning of depth);
- ``"sensor"``: rclpy's ``qos_profile_sensor_data`` (best effort, keep last 5), for
  images and other high-rate sensor streams;
- ``"latched"`` (alias ``"transient_local"``): reliable, transient local, keep last 1,
  for maps and other state a late subscriber must still receive;
- ``"reliable"``: reliable, volatile, keep last 10;
- an ``rclpy.qos.QoSProfile``, used as is.
"""

from __future__ import annotations

from typing import Any

from ..errors import ActorbtError

#: stream-buffer depth for each named setting (the latest N values are kept)
NAMED_DEPTHS = {"sensor": 5, "sensor_data": 5, "latched": 1, "transient_local": 1, "reliable": 10}


class QosError(ActorbtError, ValueError):
    """A QoS setting that is neither a depth, a known name nor a QoSProfile."""


def qos_depth(qos: Any) -> int:
    """How many messages a setting keeps: the depth of a stream actor's buffer.

    Pure Python (does not import rclpy), so the SubSystem can size buffers with it.
    """
    if isinstance(qos, bool):
        raise QosError(f"QoS must be a depth, a name or a QoSProfile, not {qos!r}")
    if isinstance(qos, int):
        return max(1, qos)
    if isinstance(qos, str):
        try:
            return NAMED_DEPTHS[qos]
        except KeyError:
            raise QosError(
                f"unknown QoS {qos!r}; expected a depth or one of {', '.join(sorted(NAMED_DEPTHS))}"
            ) from None
    depth = getattr(qos, "depth", None)
    if isinstance(depth, int):
        return max(1, depth)
    raise QosError(f"QoS must be a depth, a name or a QoSProfile, not {qos!r}")


def is_latched(qos: Any) -> bool:
    """True for a transient-local setting: ``"latched"``, ``"transient_local"`` or a
    QoSProfile with that durability (read by name: no rclpy import here)."""
    if isinstance(qos, str):
        return qos in ("latched", "transient_local")
    return getattr(getattr(qos, "durability", None), "name", "") == "TRANSIENT_LOCAL"
