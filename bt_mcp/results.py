"""MCP ``CallToolResult``s in wire form: a text for the model, structured content for
a program, and ``isError`` for anything the model should correct or know failed."""

from __future__ import annotations

from typing import Any

from .calls import CallOutcome, result_text

__all__ = ["error_result", "outcome_result", "text_result"]


def text_result(text: str, structured: dict[str, Any] | None = None) -> dict[str, Any]:
    result: dict[str, Any] = {"content": [{"type": "text", "text": text}], "isError": False}
    if structured is not None:
        result["structuredContent"] = structured
    return result


def error_result(text: str, structured: dict[str, Any] | None = None) -> dict[str, Any]:
    return {**text_result(text, structured), "isError": True}


def _times(outcome: CallOutcome) -> dict[str, Any]:
    return {"sim_time": round(outcome.sim_time, 3), "wall_time": round(outcome.wall_time, 3)}


def outcome_result(name: str, outcome: CallOutcome, is_tree: bool) -> dict[str, Any]:
    """A call's outcome: an actor's result as ``{"result": value}``; a tree's outputs
    with a summary (status, ticks, sim and wall time) and a one-line text of it."""
    if not is_tree:
        if not outcome.ok:
            return error_result(f"{name}: {outcome.error}", {"status": "FAILURE", "error": outcome.error})
        return text_result(result_text(outcome.value), {"result": outcome.value})
    summary = {"ticks": outcome.ticks, **_times(outcome)}
    when = f"after {outcome.ticks} ticks, {outcome.sim_time:.1f} s sim time ({outcome.wall_time:.1f} s wall)"
    if not outcome.ok:
        structured = {"status": "FAILURE", "error": outcome.error, "failed_at": outcome.failed_at, **summary}
        return error_result(f"{name}: {outcome.error} {when}", structured)
    outputs = outcome.value if isinstance(outcome.value, dict) else {"result": outcome.value}
    text = f"{name}: SUCCESS {when}. Outputs: {result_text(outputs)}"
    return text_result(text, {"status": "SUCCESS", "outputs": outputs, **summary})
