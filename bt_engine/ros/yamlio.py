"""Values to and from the YAML strings of the RunTree and CallActor actions.

Goals are parsed with ``yaml.safe_load`` only. Results are dumped with
``yaml.safe_dump`` after turning ROS messages, dataclasses, tuples, sets and numpy
values into plain data; whatever is left that YAML cannot hold is written as its
``repr`` string.
"""
from __future__ import annotations

import array
import dataclasses
import enum
from typing import Any

import yaml

from ..errors import ActorbtError


class GoalError(ActorbtError, ValueError):
    """A goal that cannot be run: bad YAML, bad arguments, unknown actor, busy tree."""


def to_plain(value: Any, _depth: int = 0) -> Any:
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
        return {(k if isinstance(k, (str, int, float, bool)) else repr(k)): to_plain(v, _depth + 1)
                for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset, array.array)):
        items = sorted(value, key=repr) if isinstance(value, (set, frozenset)) else value
        return [to_plain(v, _depth + 1) for v in items]
    fields = getattr(type(value), "get_fields_and_field_types", None)
    if callable(fields):  # a ROS message
        return {f: to_plain(getattr(value, f), _depth + 1) for f in fields()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_plain(getattr(value, f.name), _depth + 1)
                for f in dataclasses.fields(value)}
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist) and type(value).__module__.startswith("numpy"):
        return to_plain(tolist(), _depth + 1)
    return repr(value)


def dump(value: Any) -> str:
    """YAML text of ``value`` (see the module docstring)."""
    return yaml.safe_dump(to_plain(value), default_flow_style=None, sort_keys=False,
                          allow_unicode=True)


def _load(text: str, what: str) -> Any:
    if not text or not text.strip():
        return None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise GoalError(f"{what} is not valid YAML{where}: "
                        f"{getattr(e, 'problem', None) or e}") from None


def _check_keys(mapping: dict, what: str) -> None:
    bad = [k for k in mapping if not isinstance(k, str) or not k.isidentifier()]
    if bad:
        raise GoalError(f"{what}: keys must be argument names, not {', '.join(map(repr, bad))}")


def parse_inputs(text: str) -> dict[str, Any]:
    """RunTree ``inputs_yaml``: a mapping of input names to values (empty: none)."""
    data = _load(text, "inputs_yaml")
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise GoalError(f"inputs_yaml must be a mapping of input names to values, "
                        f"not a {type(data).__name__}")
    _check_keys(data, "inputs_yaml")
    return data


def parse_call_args(text: str) -> tuple[list[Any], dict[str, Any]]:
    """CallActor ``args_yaml`` -> (positional, keyword) arguments.

    - empty: no arguments;
    - a list: positional arguments;
    - a mapping with only ``args`` (a list) and/or ``kwargs`` (a mapping): both;
    - any other mapping: keyword arguments;
    - a single scalar: one positional argument.
    """
    data = _load(text, "args_yaml")
    if data is None:
        return [], {}
    if isinstance(data, list):
        return data, {}
    if isinstance(data, dict):
        if data and set(data) <= {"args", "kwargs"}:
            args = data.get("args") if data.get("args") is not None else []
            kwargs = data.get("kwargs") if data.get("kwargs") is not None else {}
            if not isinstance(args, list):
                raise GoalError(f"args_yaml: 'args' must be a list, not a {type(args).__name__}")
            if not isinstance(kwargs, dict):
                raise GoalError(f"args_yaml: 'kwargs' must be a mapping, not a {type(kwargs).__name__}")
            _check_keys(kwargs, "args_yaml kwargs")
            return args, kwargs
        _check_keys(data, "args_yaml")
        return [], data
    return [data], {}
