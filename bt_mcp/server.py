"""The MCP server over stdio: the SDK's low-level ``Server`` with a tools/list and a
tools/call handler, both answered by :class:`~bt_mcp.service.ToolService`.

A tree's node transitions become ``notifications/progress`` of its call (when the
client sent a progress token): ``progress`` counts them, ``message`` is
``tree:node/path status``. The protocol writes to its own duplicate of stdout
(:mod:`bt_mcp.wire`); file descriptor 1 points at stderr, so what actors and the
simulator's libraries print cannot corrupt it.
"""

from __future__ import annotations

import io
import logging
from typing import Any, BinaryIO

import anyio
import mcp_types as types
from mcp.server.context import ServerRequestContext
from mcp.server.lowlevel import Server
from mcp.server.stdio import stdio_server

from .service import ToolService

__all__ = ["build_server", "serve_stdio", "progress_message"]

log = logging.getLogger("actorbt.mcp")

INSTRUCTIONS = (
    "Each tool is a robot skill (an actor) or a mission (a behaviour tree) of actorbt. Trees report "
    "every node transition as progress. Tools annotated destructive/open-world move the robot and "
    "run only when the user allowed motion. To write a mission, check it with validate_mission, "
    "look at existing trees with show_tree, run it with run_mission, and read get_trace when it fails."
)


def progress_message(event: dict[str, Any]) -> str:
    """``bt_search:sequence/patrol running`` (the tree, the node path, the status)."""
    return f"{event['tree']}:{event['path']} {event['status']}"


def build_server(service: ToolService, version: str = "") -> Server:
    """A low-level server whose tools are ``service``'s."""

    async def list_tools(
        ctx: ServerRequestContext, params: types.PaginatedRequestParams | None
    ) -> types.ListToolsResult:
        return types.ListToolsResult.model_validate({"tools": service.list_tools()}, by_name=False)

    async def call_tool(ctx: ServerRequestContext, params: types.CallToolRequestParams) -> types.CallToolResult:
        count = 0

        async def report(event: dict[str, Any]) -> None:
            nonlocal count
            count += 1
            await ctx.session.report_progress(count, None, progress_message(event))

        try:
            result = await service.call(params.name, params.arguments, report)
        except Exception as error:  # a bug of ours must not end the session
            log.exception("tool %s failed", params.name)
            result = {
                "content": [
                    {"type": "text", "text": f"{params.name}: internal error: {type(error).__name__}: {error}"}
                ],
                "isError": True,
            }
        return types.CallToolResult.model_validate(result, by_name=False)

    return Server(
        "actorbt", version=version, instructions=INSTRUCTIONS, on_list_tools=list_tools, on_call_tool=call_tool
    )


def serve_stdio(service: ToolService, version: str = "", wire: BinaryIO | None = None) -> None:
    """Serve ``service`` on stdin and ``wire`` (default: stdout) until the client closes
    the connection."""
    server = build_server(service, version)

    async def main() -> None:
        out = anyio.wrap_file(io.TextIOWrapper(wire, encoding="utf-8", write_through=True)) if wire else None
        async with stdio_server(stdout=out) as (read_stream, write_stream):
            await server.run(read_stream, write_stream, server.create_initialization_options())

    anyio.run(main)
