"""Values in XML attributes, both ways: mission values written as port text by the
exporter, and port text read back by the importer.

A port value is one of:

- ``{key}`` or ``{key.field}``: a blackboard reference (a field path is an actorbt
  extension; BehaviorTree.CPP would read it as a key with a dot in its name);
- plain text, converted by the port's declared type (``int``, ``double``, ``bool``,
  ``std::string``), or guessed without one (numbers, ``true``/``false``, else text);
- ``json:`` and a JSON value, for what plain text cannot say (lists, mappings, null, a
  string that reads as a number or a reference). BehaviorTree.CPP v4 converts ``json:``
  text for types that have a JSON converter. Inside it, strings read as in a mission:
  a whole ``"{key}"`` is a reference and ``{{``/``}}`` are literal braces, so a list may
  hold references. Input *defaults* hold no references: their strings are plain.

The exporter writes plain text only when the importer reads it back as the same value
(:func:`encode_value` tries it), and ``json:`` otherwise.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any, Iterator

from bt_engine.trees import Ref, ValueType
from ._nodes import JSON_PREFIX, convert_literal, decode_json, python_type

__all__ = [
    "JSON_PREFIX",
    "REF_TEXT",
    "RESULT_TYPE",
    "decode_json",
    "encode_value",
    "mission_form",
    "port_type",
    "ref_keys",
    "same_value",
    "value_type_of_port",
]

#: the type of the output port of a ``<SubTree>`` model that receives the tree's whole
#: result mapping (a mission's ``do: tree, out: key``)
RESULT_TYPE = "actorbt::outputs"
#: a whole-string reference, with an optional field path (what the importer reads)
REF_TEXT = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)((?:\.[A-Za-z][A-Za-z0-9_]*)*)\}\Z")
_ANY_REF = re.compile(r"\{([^{}]*)\}\Z")

#: C++ type names for the mission value types BehaviorTree.CPP has a plain type for
_CPP_TYPES = {
    ValueType.STR: "std::string",
    ValueType.INT: "int",
    ValueType.FLOAT: "double",
    ValueType.BOOL: "bool",
    ValueType.LIST: "list",
    ValueType.DICT: "dict",
}


def port_type(vtype: ValueType) -> str:
    """The ``type`` attribute of a port holding a tree input or output ("" for any)."""
    return _CPP_TYPES.get(vtype, "")


def value_type_of_port(type_name: str) -> ValueType:
    """The mission type of a port's declared type (the inverse of :func:`port_type`;
    unknown types are ``any``)."""
    t = type_name.strip()
    if t in ("list", "dict"):
        return ValueType(t)
    annotation = python_type(t)
    return {int: ValueType.INT, float: ValueType.FLOAT, bool: ValueType.BOOL, str: ValueType.STR}.get(
        annotation, ValueType.ANY
    )


# ---------------------------------------------------------------- export


def mission_form(value: Any) -> Any:
    """A parsed mission value as its YAML would hold it: references as ``"{key.field}"``,
    literal braces in strings doubled."""
    if isinstance(value, Ref):
        return "{" + value.dotted + "}"
    if isinstance(value, str):
        return value.replace("{", "{{").replace("}", "}}")
    if isinstance(value, dict):
        return {str(k): mission_form(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [mission_form(v) for v in value]
    return value


def _plain_text(value: Any) -> str | None:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else None
    if isinstance(value, str):
        return value
    return None


def encode_value(value: Any, type_name: str = "", *, default: bool = False) -> str:
    """Port text for a parsed mission value: ``{key}`` for a reference, plain text when
    the importer reads it back as the same value, else ``json:``. ``default``: an input
    default (a plain value, whose strings are not mission strings)."""
    if isinstance(value, Ref):
        return "{" + value.dotted + "}"
    text = _plain_text(value)
    if (
        text is not None
        and not text.startswith(JSON_PREFIX)
        and _ANY_REF.match(text.strip()) is None
        and "\n" not in text
        and "\r" not in text
        and "\t" not in text
    ):
        try:
            back = convert_literal(text, type_name)
        except ValueError:
            back = _NOTHING
        if same_value(back, value):
            return text
    payload = value if default else mission_form(value)
    return JSON_PREFIX + json.dumps(payload, ensure_ascii=False, separators=(", ", ": "))


_NOTHING = object()


def same_value(a: Any, b: Any) -> bool:
    """Equal as mission values: numbers by value (an int is a float's equal), booleans
    only to booleans, references by their dotted key, containers item by item."""
    if isinstance(a, Ref) or isinstance(b, Ref):
        return isinstance(a, Ref) and isinstance(b, Ref) and a.dotted == b.dotted
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return (
            a == b
            or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))
            or math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-15)
        )
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(same_value(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


# ---------------------------------------------------------------- import


def ref_keys(value: Any) -> Iterator[str]:
    """The blackboard keys a mission-form value reads (its whole-string references)."""
    if isinstance(value, str):
        m = REF_TEXT.match(value)
        if m is not None:
            yield m.group(1)
    elif isinstance(value, dict):
        for item in value.values():
            yield from ref_keys(item)
    elif isinstance(value, list):
        for item in value:
            yield from ref_keys(item)
