"""A tool call's arguments: checked against the tool's JSON Schema before anything
runs (the SDK's low-level server leaves that to us), then turned into the actor's
positional and keyword arguments.

Every message names the argument, so a model can correct its call.
"""

from __future__ import annotations

import difflib
import inspect
from typing import Any, Mapping

import jsonschema

__all__ = ["argument_errors", "call_arguments"]


def argument_errors(schema: Mapping[str, Any], arguments: Mapping[str, Any]) -> list[str]:
    """What is wrong with ``arguments`` for ``schema``, one message per problem, in a
    stable order (empty: they fit). Limits are the schema's ``minimum`` / ``maximum``."""
    props: Mapping[str, Any] = schema.get("properties", {})
    messages: list[str] = []
    for name in schema.get("required", ()):
        if name not in arguments:
            messages.append(f"missing argument {name!r}{_about(props.get(name, {}))}")
    if schema.get("additionalProperties") is False:
        for name in arguments:
            if name not in props:
                messages.append(_unknown(name, list(props)))
    validator = jsonschema.Draft202012Validator(schema)
    for error in sorted(validator.iter_errors(dict(arguments)), key=lambda e: list(map(str, e.absolute_path))):
        if error.validator in ("required", "additionalProperties"):
            continue  # said above, by name
        messages.append(f"argument {_where(error)}: {error.message}")
    return messages


def _about(schema: Mapping[str, Any]) -> str:
    text = schema.get("description")
    kind = schema.get("type")
    if kind and text:
        return f" ({kind}: {text})"
    return f" ({kind or text})" if kind or text else ""


def _unknown(name: str, known: list[str]) -> str:
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    expected = ", ".join(known) or "none"
    return f"unknown argument {name!r}{hint} (expected: {expected})"


def _where(error: jsonschema.ValidationError) -> str:
    """``'speed'``, or ``'q'[2]`` for an item of an array argument."""
    path = list(error.absolute_path)
    if not path:
        return "(all)"
    head, rest = path[0], path[1:]
    return repr(head) + "".join(f"[{p!r}]" if isinstance(p, int) else f".{p}" for p in rest)


def call_arguments(
    signature: inspect.Signature, arguments: Mapping[str, Any]
) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """``arguments`` by name -> ``(args, kwargs)`` for an actor with ``signature``.

    A ``*args`` parameter arrives as an array under its name: its values, and the
    parameters before it, are then passed by position (the only way Python takes them).
    """
    params = list(signature.parameters.values())
    variadic = next((p for p in params if p.kind is p.VAR_POSITIONAL), None)
    rest = dict(arguments)
    args: list[Any] = []
    by_position = variadic is not None and variadic.name in rest
    for p in params:
        if p.kind is p.POSITIONAL_ONLY or (by_position and p.kind is p.POSITIONAL_OR_KEYWORD):
            if p.name in rest:
                args.append(rest.pop(p.name))
            elif p.default is not p.empty:
                args.append(p.default)
            else:
                break  # missing: the signature check names it
        elif p is variadic:
            args.extend(rest.pop(p.name, None) or ())
            break
    return tuple(args), rest
