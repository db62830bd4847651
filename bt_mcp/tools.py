"""Catalog entries as MCP tools, in the protocol's wire form (plain dicts).

A tool is the catalog's JSON-Schema description of one actor or tree
(:func:`bt_engine.catalog.tool_schema`): its name is the actor's path, its input
schema the catalog's ``parameters`` (closed with ``additionalProperties: false``
unless the actor takes ``**kwargs``, so a misspelt argument is refused by name), and
its annotations say what the actor declared: ``readOnlyHint`` for a query,
``destructiveHint`` and ``openWorldHint`` for one that moves the robot.
"""

from __future__ import annotations

import inspect
from typing import Any, Mapping

from .settings import MOTION_HOW_TO

__all__ = ["input_schema", "mcp_tool", "tool_description"]


def input_schema(tool: Mapping[str, Any], signature: inspect.Signature | None = None) -> dict[str, Any]:
    """The catalog's parameters as an MCP ``inputSchema``: closed unless the signature
    takes ``**kwargs`` (then any other argument is the actor's business)."""
    schema = dict(tool.get("parameters") or {"type": "object", "properties": {}})
    open_ended = signature is not None and any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values())
    if not open_ended:
        schema["additionalProperties"] = False
    return schema


def tool_description(tool: Mapping[str, Any], allow_motion: bool) -> str:
    """What a model reads: the summary, the details, what it returns, and whether it
    moves the robot (and, when this server refuses that, how a user allows it)."""
    parts = [str(tool.get("description") or tool["name"])]
    if tool.get("details"):
        parts.append(str(tool["details"]))
    returns = tool.get("returns") or {}
    if returns.get("description"):
        parts.append(f"Returns: {returns['description']}")
    if tool.get("moves"):
        parts.append(
            "Moves the robot."
            if allow_motion
            else f"Moves the robot: refused while motion is off (to allow it, {MOTION_HOW_TO})."
        )
    return "\n\n".join(parts)


def mcp_tool(
    tool: Mapping[str, Any], signature: inspect.Signature | None = None, *, allow_motion: bool = False
) -> dict[str, Any]:
    """One catalog entry as an MCP ``Tool``."""
    moves, read_only = bool(tool.get("moves")), bool(tool.get("read_only"))
    annotations: dict[str, Any] = {"title": tool["name"], "readOnlyHint": read_only, "openWorldHint": moves}
    if not read_only:  # (the hint means nothing for a read-only tool)
        annotations["destructiveHint"] = moves
    if read_only:
        annotations["idempotentHint"] = True
    return {
        "name": tool["name"],
        "description": tool_description(tool, allow_motion),
        "inputSchema": input_schema(tool, signature),
        "annotations": annotations,
        "_meta": {
            "actorbt": {
                "kind": tool.get("kind"),
                "is_tree": bool(tool.get("is_tree")),
                "moves": moves,
                "read_only": read_only,
                "motion_allowed": allow_motion if moves else None,
            }
        },
    }
