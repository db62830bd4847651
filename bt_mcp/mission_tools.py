"""The tools for a model that writes missions: ``validate_mission`` (YAML text in;
errors located by line and column, with the validator's suggestions, out),
``run_mission`` (validated, then run with progress), ``show_tree`` (a tree as text)
and ``get_trace`` (the events of the last tree run).

Drafts are checked exactly as ``actorbt check`` checks files: against the actors of
the runtime and the trees of its library. They are run without being registered, so
the tool list does not change.
"""

from __future__ import annotations

from typing import Any

from bt_engine.errors import ActorbtError
from bt_engine.trees import Mission, MissionError, TreeHost, parse_mission, validate_mission
from bt_tools.show import ascii_tree

__all__ = ["DRAFT_FILE", "MISSION_TOOLS", "check_draft", "error_entries", "trace_result"]

#: the file name a draft's errors are located in
DRAFT_FILE = "mission.yaml"

_YAML = {
    "type": "string",
    "description": "the mission as YAML text (name:, inputs:, outputs:, root:), as in the trees folder",
}

#: the mission tools in MCP wire form (actors and trees come from the catalog)
MISSION_TOOLS: list[dict[str, Any]] = [
    {
        "name": "validate_mission",
        "description": "Check a mission (a behaviour tree in YAML) without running it: its YAML, its nodes, "
        "the actors it calls and their arguments, blackboard references and check: expressions. "
        "Returns every error as line:column: message, with close matches for misspelt names.",
        "inputSchema": {
            "type": "object",
            "properties": {"yaml": _YAML},
            "required": ["yaml"],
            "additionalProperties": False,
        },
        "annotations": {
            "title": "validate_mission",
            "readOnlyHint": True,
            "idempotentHint": True,
            "openWorldHint": False,
        },
    },
    {
        "name": "run_mission",
        "description": "Validate a mission (a behaviour tree in YAML) and, when it is valid, run it; progress "
        "notifications tell every node transition. Returns its outputs and a summary. A mission "
        "that calls an actor that moves the robot runs only where the server allows motion.",
        "inputSchema": {
            "type": "object",
            "properties": {
                "yaml": _YAML,
                "inputs": {"type": "object", "description": "values of the mission's inputs by name", "default": {}},
            },
            "required": ["yaml"],
            "additionalProperties": False,
        },
        "annotations": {"title": "run_mission", "readOnlyHint": False, "destructiveHint": True, "openWorldHint": True},
    },
    {
        "name": "show_tree",
        "description": "A tree as indented text, one node per line: a tree of the catalog by name, or a "
        "mission given as YAML text.",
        "inputSchema": {
            "type": "object",
            "properties": {
                "tree": {"type": "string", "description": "the name of a tree of the catalog"},
                "yaml": _YAML,
            },
            "additionalProperties": False,
        },
        "annotations": {"title": "show_tree", "readOnlyHint": True, "idempotentHint": True, "openWorldHint": False},
    },
    {
        "name": "get_trace",
        "description": "The events of the last tree run (a tree tool or run_mission): runs, ticks, node status "
        "changes, actor calls and returns, blackboard writes, the end; each stamped with the "
        "runtime clock t [s].",
        "inputSchema": {
            "type": "object",
            "properties": {
                "limit": {
                    "type": "integer",
                    "minimum": 1,
                    "maximum": 5000,
                    "default": 500,
                    "description": "at most this many events, the last ones",
                },
                "types": {
                    "type": "array",
                    "description": "only events of these types (default: all)",
                    "items": {"enum": ["run", "tick", "status", "call", "return", "write", "end"]},
                },
            },
            "additionalProperties": False,
        },
        "annotations": {"title": "get_trace", "readOnlyHint": True, "openWorldHint": False},
    },
]


def check_draft(host: TreeHost, text: str) -> tuple[Mission | None, list[MissionError]]:
    """Parse and validate a draft against the host's actors and trees: the mission (or
    ``None`` when it does not parse) and every problem, by position."""
    try:
        mission = parse_mission(text, file=DRAFT_FILE)
    except MissionError as error:  # YAML or structure: the first problem only
        return None, [error]
    trees = {m.name: m for m in host.library}
    trees[mission.name] = mission
    errors = validate_mission(mission, host.library.resolve, behaviours=host.behaviours, trees=trees)
    return mission, errors


def error_entries(errors: list[MissionError]) -> list[dict[str, Any]]:
    """Errors as ``{line, column, message, kind}`` (the message carries the suggestion)."""
    return [
        {"line": e.pos.line, "column": e.pos.column, "message": e.message, "kind": type(e).__name__} for e in errors
    ]


def errors_text(errors: list[MissionError]) -> str:
    return "\n".join(f"{e.pos.line}:{e.pos.column}: {e.message}" for e in errors)


def show_text(host: TreeHost, tree: str | None, text: str | None) -> str:
    """``show_tree``: a library tree by name, or a draft (parsed only: drawing needs no actor).

    Raises:
        ActorbtError: neither or both given, an unknown tree, or a draft that does not parse.
    """
    if (tree is None) == (text is None):
        raise ActorbtError("give either 'tree' (a tree's name) or 'yaml' (a mission's text)")
    if text is not None:
        return ascii_tree(parse_mission(text, file=DRAFT_FILE))
    if tree not in host.library.names:
        import difflib

        close = difflib.get_close_matches(str(tree), host.library.names, n=3)
        hint = f"; did you mean {', '.join(map(repr, close))}?" if close else ""
        raise ActorbtError(f"no tree {tree!r}{hint} (trees: {', '.join(host.library.names) or 'none'})")
    return ascii_tree(host.library[tree])


def trace_result(last: dict[str, Any] | None, limit: int = 500, types: list[str] | None = None) -> dict[str, Any]:
    """``get_trace``'s structured content from the last run kept by the server."""
    if last is None:
        return {"tool": None, "events": [], "note": "no tree has run on this server yet"}
    events = [e for e in last["events"] if types is None or e.get("type") in types]
    omitted = max(0, len(events) - limit) + last.get("dropped", 0)
    return {
        "tool": last["tool"],
        "arguments": last["arguments"],
        "outcome": last["outcome"],
        "events": events[-limit:],
        "omitted": omitted,
    }
