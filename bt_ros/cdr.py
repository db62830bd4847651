"""ROS 2 messages as CDR bytes and their definitions, for a rosbag2 writer and Foxglove.

    serialize(msg)         the CDR bytes DDS would carry (rclpy's own serializer)
    typestore()            rosbags' Jazzy type store: every standard message definition
    message_definition(t)  ``t``'s definition with its dependencies (``ros2msg`` text), as
                           rosbag2 stores it and Foxglove decodes ``cdr`` channels with it
    type_hash(t)           ``RIHS01_...``: the type hash Jazzy advertises

The bytes come from rclpy, the definitions from rosbags: both are Jazzy's interfaces, so
a bag or a Foxglove channel decodes with tools that know nothing of actorbt.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

from bt_engine.bus.messages import RosMessage
from bt_engine.errors import ActorbtError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["UnknownDefinitionError", "message_definition", "serialize", "type_hash", "typestore"]


class UnknownDefinitionError(ActorbtError, LookupError):
    """A message type the rosbags type store does not define."""


def serialize(msg: RosMessage) -> bytes:
    """``msg`` (a ROS 2 Python message) as CDR bytes, encapsulation header included."""
    from rclpy.serialization import serialize_message

    return serialize_message(msg)


@functools.lru_cache(maxsize=1)
def typestore() -> Typestore:
    """rosbags' type store for ROS 2 Jazzy (built once: it is immutable)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _known(name: str) -> str:
    if name not in typestore().types:
        raise UnknownDefinitionError(f"no message definition for {name} in rosbags' Jazzy type store")
    return name


@functools.lru_cache(maxsize=None)
def message_definition(name: str) -> str:
    """The ``ros2msg`` definition of ``name`` (``pkg/msg/Name``), dependencies appended."""
    text, _ = typestore().generate_msgdef(_known(name), ros_version=2)
    return text


@functools.lru_cache(maxsize=None)
def type_hash(name: str) -> str:
    """The RIHS01 type hash of ``name``."""
    return typestore().hash_rihs01(_known(name))
