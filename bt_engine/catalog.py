"""The catalog: every actor's path, docstring, signature and kind, and its export as
JSON-Schema tool descriptions so a planner or an LLM can choose and call actors."""
from __future__ import annotations

import inspect
import typing
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .actor import ActorRef
    from .subsystem import SubSystem

_JSON_TYPES: dict[Any, str] = {int: "integer", float: "number", str: "string", bool: "boolean",
                               list: "array", tuple: "array", dict: "object", type(None): "null"}


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
        return {"type": "object", "description": f"{annotation.__module__}.{annotation.__qualname__}"}
    return {}


def _resolved_hints(ref: "ActorRef") -> dict[str, Any]:
    try:
        return typing.get_type_hints(ref.fn)
    except Exception:
        return {}


def describe(ref: "ActorRef") -> dict[str, Any]:
    """One actor as a plain dict: path, kind, doc, signature, tree or not."""
    return {"path": ref.path, "name": ref.name, "kind": ref.kind.value, "is_tree": ref.is_tree,
            "signature": f"{ref.path}{ref.signature}", "doc": ref.doc}


def tool_schema(ref: "ActorRef") -> dict[str, Any]:
    """One actor as a JSON-Schema tool description."""
    hints = _resolved_hints(ref)
    props: dict[str, Any] = {}
    required: list[str] = []
    variadic = None
    for p in ref.signature.parameters.values():
        ann = hints.get(p.name, p.annotation)
        if p.kind is p.VAR_POSITIONAL:
            variadic = {"type": "array", "items": json_type(ann)} if json_type(ann) else {"type": "array"}
            props[p.name] = {**variadic, "description": "positional values (*args)"}
            continue
        if p.kind is p.VAR_KEYWORD:
            continue
        schema = dict(json_type(ann))
        if p.default is p.empty:
            required.append(p.name)
        elif _jsonable(p.default):
            schema["default"] = p.default
        props[p.name] = schema
    summary = ref.doc.split("\n\n")[0].replace("\n", " ") if ref.doc else ""
    return {
        "name": ref.path,
        "description": summary or f"{ref.kind.value} actor {ref.path}",
        "kind": ref.kind.value,
        "is_tree": ref.is_tree,
        "parameters": {"type": "object", "properties": props, "required": required},
    }


def _jsonable(v: Any) -> bool:
    return v is None or isinstance(v, (bool, int, float, str, list, dict, tuple))


def catalog(root: "SubSystem") -> list[dict[str, Any]]:
    """Every actor below ``root``, sorted by path."""
    return [describe(r) for r in sorted(root.all_actors(), key=lambda r: r.path)]


def tool_schemas(root: "SubSystem") -> list[dict[str, Any]]:
    return [tool_schema(r) for r in sorted(root.all_actors(), key=lambda r: r.path)]
