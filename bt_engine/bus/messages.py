"""ROS messages as plain data, and ROS type names; duck-typed, so rclpy is not imported.

    type_name(cls)        'sensor_msgs/msg/LaserScan' of a message, service or action class
    message_class(name)   the class of 'sensor_msgs/msg/LaserScan' ('sensor_msgs/LaserScan'
                          and 'sensor_msgs.msg.LaserScan' work too)
    to_plain(msg, ...)    a message as dicts, lists and scalars under its ROS field names,
                          long arrays and strings shortened (what ``actorbt topic echo`` prints)

``to_plain`` is for looking at messages: it cuts sequences and strings as ``ros2 topic
echo`` does (the first ``truncate`` items, then ``'...'``), or leaves arrays of numbers,
booleans and bytes out (``arrays=False``: ``'<sequence<float>, length: 360>'``). Arrays
of messages and of strings stay (their items' own numeric arrays left out): they are what
a reader looks for, the frames of /tf_static's ``transforms``, a JointState's names.
``ros2 topic echo --no-arr`` leaves every array out, those too. Values that must survive whole
(an actor's result sent over ROS) go through :func:`bt_ros.yamlio.to_plain`.
"""

from __future__ import annotations

import array
import importlib
import math
import struct
from typing import Any, ClassVar, Protocol

from ..errors import ActorbtError

__all__ = ["RosAction", "RosMessage", "RosService", "UnknownTypeError", "message_class", "to_plain", "type_name"]


class RosMessage(Protocol):
    """A ROS message (rosidl generates its class): made from keyword fields (a default
    instance from ``cls()``), its fields are attributes, and the class lists them with
    their ROS types."""

    def __init__(self, **fields: Any) -> None: ...

    def __getattr__(self, field: str) -> Any: ...

    def __setattr__(self, field: str, value: Any) -> None: ...

    @classmethod
    def get_fields_and_field_types(cls) -> dict[str, str]: ...


class RosAction(Protocol):
    """What the bus needs of a ROS action class: its three message classes."""

    Goal: ClassVar[type[RosMessage]]
    Result: ClassVar[type[RosMessage]]
    Feedback: ClassVar[type[RosMessage]]
    #: rosidl's services and topics the action is made of (SendGoalService,
    #: FeedbackMessage, ...), which a client that subscribes on its own needs
    Impl: ClassVar[Any]


class RosService(Protocol):
    """What the bus needs of a ROS service class: its two message classes."""

    Request: ClassVar[type[RosMessage]]
    Response: ClassVar[type[RosMessage]]


#: how many items of a sequence (characters of a string) are shown by default (ros2's)
TRUNCATE = 128


class UnknownTypeError(ActorbtError, LookupError):
    """A ROS type name that names no importable message, service or action class."""


def type_name(cls: type) -> str:
    """``package/msg/Name`` (``srv``, ``action``) of a ROS interface class."""
    parts = [p for p in cls.__module__.split(".") if not p.startswith("_")]
    return "/".join(parts + [cls.__name__])


def message_class(name: str) -> type:
    """The class a ROS type name names: ``pkg/msg/Name``, ``pkg/Name`` (a message) or
    ``pkg.msg.Name``."""
    parts = name.replace(".", "/").strip("/").split("/")
    if len(parts) == 2:
        parts.insert(1, "msg")
    if len(parts) != 3 or not all(parts):
        raise UnknownTypeError(f"{name!r} is no ROS type name (expected package/msg/Name)")
    package, kind, cls_name = parts
    try:
        module = importlib.import_module(f"{package}.{kind}")
        return getattr(module, cls_name)
    except (ImportError, AttributeError) as e:
        raise UnknownTypeError(f"type {name} is not installed here ({e})") from None


def _is_message(value: Any) -> bool:
    return callable(getattr(type(value), "get_fields_and_field_types", None))


def _is_sequence(value: Any) -> bool:
    if isinstance(value, (list, tuple, array.array, bytes, bytearray)):
        return True
    return type(value).__module__ == "numpy" and getattr(value, "ndim", 0) > 0


def to_plain(msg: Any, *, truncate: int | None = TRUNCATE, arrays: bool = True, finite: bool = False) -> Any:
    """``msg`` as plain data (see the module docstring).

    Args:
        truncate: keep this many items of each sequence and characters of each string,
            then ``'...'``; ``None`` keeps everything.
        arrays: ``False`` leaves sequences of numbers, booleans and bytes out, as
            ``'<TYPE, length: N>'``; sequences of messages and strings stay.
        finite: NaN and infinities become ``None`` (for JSON, which has neither).
    """
    return _plain(msg, None, truncate, arrays, finite)


def _plain(value: Any, ros_type: str | None, truncate: int | None, arrays: bool, finite: bool) -> Any:
    if value is None or isinstance(value, (bool, int)):
        return value
    if isinstance(value, float):  # numpy's float64 is one too
        if not math.isfinite(value):
            return None if finite else float(value)
        return _short32(value) if ros_type == "float" else float(value)
    if isinstance(value, str):
        if truncate is not None and len(value) > truncate:
            return value[:truncate] + "..."
        return value
    if _is_message(value):
        fields = type(value).get_fields_and_field_types()
        return {name: _plain(getattr(value, name), t, truncate, arrays, finite) for name, t in fields.items()}
    if _is_sequence(value):
        if not arrays and _primitive_items(value, ros_type):
            return f"<{ros_type or 'sequence'}, length: {len(value)}>"
        items = value[:truncate] if truncate is not None and len(value) > truncate else value
        single = _is_float32(value, ros_type)
        if type(items).__module__ == "numpy":
            items = items.tolist()
        element = "float" if single else None
        plain = [_plain(_item(v), element, truncate, arrays, finite) for v in items]
        if len(items) < len(value):
            plain.append("...")
        return plain
    item = getattr(value, "item", None)  # a numpy scalar
    if callable(item) and type(value).__module__ == "numpy":
        return _plain(item(), ros_type, truncate, arrays, finite)
    return repr(value)


def _primitive_items(seq: Any, ros_type: str | None) -> bool:
    """Whether ``seq`` holds numbers, booleans or bytes (not messages, not strings): by
    its field type (``sequence<double>``, ``double[9]``, ``sequence<pkg/Msg, 10>``), else
    by its first item (a ROS sequence holds one type)."""
    element = _element_type(ros_type)
    if element is not None:
        return "/" not in element and not element.startswith(("string", "wstring"))
    if isinstance(seq, (list, tuple)):
        return not seq or not (isinstance(seq[0], str) or _is_message(seq[0]))
    return True  # array.array, numpy, bytes


def _element_type(ros_type: str | None) -> str | None:
    """The item type of a sequence or array field type; None if ``ros_type`` is neither."""
    if not ros_type:
        return None
    if ros_type.startswith("sequence<") and ros_type.endswith(">"):
        return ros_type[len("sequence<") : -1].split(",")[0].strip()
    if ros_type.endswith("]") and "[" in ros_type:
        return ros_type[: ros_type.rindex("[")]
    return None


def _is_float32(seq: Any, ros_type: str | None) -> bool:
    """Whether a sequence holds float32 values (ROS ``float``)."""
    if isinstance(seq, array.array):
        return seq.typecode == "f"
    dtype = getattr(seq, "dtype", None)
    if dtype is not None:
        return str(dtype) == "float32"
    return ros_type is not None and (ros_type.startswith("float[") or ros_type.startswith("sequence<float"))


def _short32(x: float) -> float:
    """The shortest decimal that is the same float32 as ``x`` (0.1f shows as 0.1, not
    0.10000000149011612)."""
    single = struct.unpack("f", struct.pack("f", x))[0]
    for digits in range(6, 10):
        shorter = float(f"{x:.{digits}g}")
        if struct.unpack("f", struct.pack("f", shorter))[0] == single:
            return shorter
    return x


def _item(value: Any) -> Any:
    """One element of a sequence: a ``byte`` field's items are 1-byte ``bytes``."""
    if isinstance(value, bytes) and len(value) == 1:
        return value[0]
    return value
