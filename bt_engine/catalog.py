"""The catalog: every actor's path, docstring, signature and kind, and its export as
JSON-Schema tool descriptions so a planner or an LLM can choose and call actors.

Parameter descriptions and units come from the actors' ``Args:`` docstring sections
(see :mod:`bt_engine.docstrings`), a tree's from its inputs' ``doc:``."""

from __future__ import annotations

import collections.abc
import dataclasses
import inspect
import sys
import typing
from typing import TYPE_CHECKING, Any, Mapping

from .actor import NO_SAFETY
from .docstrings import Docstring, unit_of
from .docstrings import explicit as explicit_docs
from .docstrings import parse as parse_docstring

if TYPE_CHECKING:
    from .actor import ActorRef
    from .subsystem import SubSystem

_JSON_TYPES: dict[type, str] = {
    int: "integer",
    float: "number",
    str: "string",
    bool: "boolean",
    list: "array",
    tuple: "array",
    dict: "object",
    type(None): "null",
}


def json_type(annotation: Any) -> dict[str, Any]:
    """A JSON-Schema fragment for a Python type hint ({} when unknown)."""
    if annotation is inspect.Parameter.empty or annotation is Any:
        return {}
    if isinstance(annotation, str):  # postponed annotations we cannot resolve
        return {"description": f"type: {annotation}"}
    origin = typing.get_origin(annotation)
    if origin is typing.Union or str(origin) == "<class 'types.UnionType'>":
        parts = [json_type(a) for a in typing.get_args(annotation)]
        return {"anyOf": parts} if all(parts) else {}
    if origin in (list, tuple, typing.Sequence):
        args = typing.get_args(annotation)
        item = json_type(args[0]) if args else {}
        return {"type": "array", **({"items": item} if item else {})}
    if origin is dict:
        return {"type": "object"}
    if origin is typing.Literal:
        return {"enum": list(typing.get_args(annotation))}
    t = _JSON_TYPES.get(annotation)
    if t is not None:
        return {"type": t}
    if isinstance(annotation, type):
        return {"type": "object", "description": _public_name(annotation)}
    return {}


def _public_name(cls: type) -> str:
    """``module.Class`` as users import it: private modules that the package re-exports
    the class from are left out (``geometry_msgs.msg.Twist``, not ``..._twist.Twist``)."""
    module = cls.__module__
    while "." in module:
        parent, _, last = module.rpartition(".")
        if not last.startswith("_") or getattr(sys.modules.get(parent), cls.__qualname__, None) is not cls:
            break
        module = parent
    return f"{module}.{cls.__qualname__}"


def _resolved_hints(ref: "ActorRef") -> dict[str, Any]:
    try:
        return typing.get_type_hints(ref.fn)
    except Exception:
        return {}


def _annotation(annotation: Any, hints: dict[str, Any], name: str) -> Any:
    """The signature's annotation (what a caller passes: an explicit signature, such as a
    publisher's, is more precise than the function's own hints), resolved by the hints
    when it is postponed text."""
    if annotation is inspect.Parameter.empty or isinstance(annotation, str):
        return hints.get(name, annotation)
    return annotation


def docs_of(ref: "ActorRef") -> Docstring:
    """The actor's docstring split for the catalog, with the parameter docs attached by
    :func:`bt_engine.docstrings.param_docs` (or a tree's input docs) in ``params``."""
    doc = parse_docstring(ref.doc)
    params, returns = explicit_docs(ref.fn)
    if params or isinstance(returns, str):
        doc = dataclasses.replace(
            doc, params={**doc.params, **params}, returns=returns if isinstance(returns, str) else doc.returns
        )
    return doc


def doc_problems(ref: "ActorRef") -> list[str]:
    """What the actor's parameter docs lack: parameters without a description, and
    documented names that are no parameter (a typo, or a renamed parameter)."""
    params = ref.signature.parameters
    documented = docs_of(ref).params
    problems = [
        f"{ref.path}: parameter {n!r} has no description"
        for n, p in params.items()
        if p.kind is not p.VAR_KEYWORD and not documented.get(n, "").strip()
    ]
    problems += [f"{ref.path}: documents {n!r}, which is no parameter" for n in documented if n not in params]
    return problems


def describe(ref: "ActorRef") -> dict[str, Any]:
    """One actor as a plain dict: path, kind, doc, signature, tree or not."""
    return {
        "path": ref.path,
        "name": ref.name,
        "kind": ref.kind.value,
        "is_tree": ref.is_tree,
        "signature": f"{ref.path}{ref.signature}",
        "doc": ref.doc,
    }


def tool_schema(ref: "ActorRef") -> dict[str, Any]:
    """One actor as a JSON-Schema tool description.

    ``description`` is the docstring's summary and ``details`` the rest of it (without
    the ``Args:`` and ``Returns:`` sections). Each parameter has its JSON type (from the
    type hint, else from the default), ``description`` (its ``Args:`` entry), ``unit``
    (the ``[unit]`` in that text) and ``default``; a declared limit is its ``minimum``
    / ``maximum`` (of each value, for ``*args``). ``returns`` describes the result (of
    a stream: each value; of a tree: its outputs). ``moves`` (it commands motion of the
    robot) and ``read_only`` (it changes nothing) are what the actor declares (a tree:
    what the actors it calls declare), see :class:`~bt_engine.actor.Safety`.
    """
    safety = getattr(ref, "safety", None) or NO_SAFETY
    hints = _resolved_hints(ref)
    docs = docs_of(ref)
    props: dict[str, Any] = {}
    required: list[str] = []
    for p in ref.signature.parameters.values():
        if p.kind is p.VAR_KEYWORD:
            continue
        ann = _annotation(p.annotation, hints, p.name)
        text = docs.params.get(p.name, "").strip()
        if p.kind is p.VAR_POSITIONAL:
            item = json_type(ann)
            schema = {"type": "array", **({"items": item} if item else {})}
            text = text + _VARIADIC.format(name=p.name) if text else "positional values (*args)"
        else:
            schema = dict(json_type(ann)) or _type_of_default(p.default)
        props[p.name] = _bounded(_described(schema, text), safety.limits.get(p.name), p.kind is p.VAR_POSITIONAL)
        if p.kind is p.VAR_POSITIONAL:
            continue
        if p.default is p.empty:
            required.append(p.name)
        elif _jsonable(p.default):
            props[p.name]["default"] = p.default
    tool: dict[str, Any] = {"name": ref.path, "description": docs.summary or f"{ref.kind.value} actor {ref.path}"}
    if docs.details:
        tool["details"] = docs.details
    tool.update(
        {
            "kind": ref.kind.value,
            "is_tree": ref.is_tree,
            "moves": safety.moves,
            "read_only": safety.read_only,
            "parameters": {"type": "object", "properties": props, "required": required},
        }
    )
    returns = _returns(ref, hints, docs)
    if returns:
        tool["returns"] = returns
    return tool


def _bounded(schema: dict[str, Any], limit: "tuple[float | None, float | None] | None", each: bool) -> dict[str, Any]:
    """``schema`` with a declared limit as ``minimum`` / ``maximum`` (of its items when
    ``each``: a ``*args`` parameter)."""
    if limit is None:
        return schema
    bounds = {k: v for k, v in zip(("minimum", "maximum"), limit) if v is not None}
    if each:
        return {**schema, "items": {**schema.get("items", {}), **bounds}}
    return {**schema, **bounds}


#: what a variadic parameter's description ends with
_VARIADIC = " (positional values, *{name})"


def _described(schema: dict[str, Any], text: str) -> dict[str, Any]:
    """``schema`` with ``description`` (a type's own description kept in parentheses) and
    the ``unit`` the text names."""
    if not text:
        return schema
    out = dict(schema)
    own = out.pop("description", None)
    out["description"] = f"{text} ({own})" if own else text
    unit = unit_of(text)
    if unit:
        out["unit"] = unit
    return out


def _type_of_default(default: Any) -> dict[str, Any]:
    """The JSON type of a default value, for a parameter without a type hint."""
    if default is inspect.Parameter.empty or default is None:
        return {}
    t = _JSON_TYPES.get(type(default))
    return {"type": t} if t else {}


_ITERATORS = {
    collections.abc.Iterator,
    collections.abc.Iterable,
    collections.abc.Generator,
    collections.abc.AsyncIterator,
    collections.abc.AsyncGenerator,
}


def _returns(ref: "ActorRef", hints: dict[str, Any], docs: Docstring) -> dict[str, Any]:
    """The result's JSON-Schema fragment: from the return hint (a stream's: the type of
    each value) and the ``Returns:`` text; or the one attached explicitly (a tree's)."""
    _, explicit = explicit_docs(ref.fn)
    if isinstance(explicit, Mapping):
        return dict(explicit)
    ann = _annotation(ref.signature.return_annotation, hints, "return")
    if typing.get_origin(ann) in _ITERATORS:
        args = typing.get_args(ann)
        ann = args[0] if args else inspect.Parameter.empty
    return _described(dict(json_type(ann)), docs.returns)


def _jsonable(v: Any) -> bool:
    return v is None or isinstance(v, (bool, int, float, str, list, dict, tuple))


# -- the text form -------------------------------------------------------------------------
def text_lines(doc: str | None, tool: Mapping[str, Any]) -> list[str]:
    """What ``actorbt catalog`` prints below an actor's signature: its docstring without
    the ``Args:`` / ``Returns:`` sections, then one line per parameter, e.g.
    ``x: goal x [m] (number, required)``, and what it returns when that is described
    (a tree's outputs, one per line)."""
    tree = bool(tool.get("is_tree"))
    lines = (parse_docstring(doc).text or "(no docstring)").splitlines()
    if tool.get("moves"):  # what a careful caller must know first
        lines.append("Moves the robot.")
    params = tool.get("parameters", {})
    props: Mapping[str, Any] = params.get("properties", {})
    if props:
        lines.append("Inputs:" if tree else "Args:")
        required = set(params.get("required", ()))
        for name, schema in props.items():
            lines.append(f"  {_param_line(name, schema, name in required)}")
    returns = tool.get("returns") or {}
    outputs = returns.get("properties") if tree else None
    if outputs:
        lines.append("Outputs:")
        lines += [f"  {_param_line(name, schema, None)}" for name, schema in outputs.items()]
    elif parse_docstring(doc).returns:  # (the type alone is in the signature above)
        lines.append(f"Returns: {returns.get('description', '')} ({type_text(returns)})")
    return lines


def _param_line(name: str, schema: Mapping[str, Any], required: bool | None) -> str:
    notes = [type_text(schema)]
    bounds = schema.get("items", schema) if schema.get("type") == "array" else schema
    if "minimum" in bounds or "maximum" in bounds:
        notes.append(f"{bounds.get('minimum', '-inf')} to {bounds.get('maximum', 'inf')}")
    if required:
        notes.append("required")
    elif "default" in schema:
        notes.append(f"default {schema['default']!r}")
    text = schema.get("description", "")
    variadic = _VARIADIC.format(name=name)
    if text.endswith(variadic):
        name, text = f"*{name}", text[: -len(variadic)]
    return f"{name}: {text} ({', '.join(notes)})" if text else f"{name} ({', '.join(notes)})"


def type_text(schema: Mapping[str, Any]) -> str:
    """A JSON-Schema fragment's type in words: ``number``, ``array of number``,
    ``string or null``, ``one of 'a', 'b'``; ``any`` when it has none."""
    if "anyOf" in schema:
        return " or ".join(type_text(s) for s in schema["anyOf"])
    if "enum" in schema:
        return "one of " + ", ".join(repr(v) for v in schema["enum"])
    t = schema.get("type")
    if isinstance(t, list):
        return " or ".join(t)
    if t == "array" and schema.get("items"):
        return f"array of {type_text(schema['items'])}"
    return t or "any"


def catalog(root: "SubSystem") -> list[dict[str, Any]]:
    """Every actor below ``root``, sorted by path."""
    return [describe(r) for r in sorted(root.all_actors(), key=lambda r: r.path)]


def tool_schemas(root: "SubSystem") -> list[dict[str, Any]]:
    return [tool_schema(r) for r in sorted(root.all_actors(), key=lambda r: r.path)]
