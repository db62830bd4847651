"""Values as the YAML text of the RunTree and CallActor actions (results, and the
arguments a client sends).

Values are dumped with ``yaml.safe_dump`` after turning ROS messages, dataclasses,
tuples, sets and numpy values into plain data; whatever is left that YAML cannot hold is
written as its ``repr`` string. The way back in, a goal's text to validated arguments,
is :mod:`bt_ros.goals`.
"""

from __future__ import annotations

import array
import dataclasses
import enum
import yaml

from .rostypes import Value


def to_plain(value: Value, _depth: int = 0) -> Value:
    """``value`` as YAML-safe data (dict, list, str, int, float, bool, None)."""
    if _depth > 50:
        return repr(value)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, enum.Enum):
        return to_plain(value.value, _depth + 1)
    if isinstance(value, bytes):
        return list(value)
    if isinstance(value, dict):
        return {
            (k if isinstance(k, (str, int, float, bool)) else repr(k)): to_plain(v, _depth + 1)
            for k, v in value.items()
        }
    if isinstance(value, (list, tuple, set, frozenset, array.array)):
        items = sorted(value, key=repr) if isinstance(value, (set, frozenset)) else value
        return [to_plain(v, _depth + 1) for v in items]
    fields = getattr(type(value), "get_fields_and_field_types", None)
    if callable(fields):  # a ROS message
        return {f: to_plain(getattr(value, f), _depth + 1) for f in fields()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_plain(getattr(value, f.name), _depth + 1) for f in dataclasses.fields(value)}
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist) and type(value).__module__.startswith("numpy"):
        return to_plain(tolist(), _depth + 1)
    return repr(value)


def dump(value: Value) -> str:
    """YAML text of ``value`` (see the module docstring)."""
    return yaml.safe_dump(to_plain(value), default_flow_style=None, sort_keys=False, allow_unicode=True)


def flow(value: Value) -> str:
    """``value`` as one line of YAML flow style, e.g. ``{category: can, n: 2}``."""
    return (
        yaml.safe_dump(to_plain(value), default_flow_style=True, sort_keys=False, allow_unicode=True, width=1 << 30)
        .strip()
        .removesuffix("\n...")
        .strip()
    )
