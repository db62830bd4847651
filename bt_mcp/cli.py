"""``actorbt mcp``: the catalog as an MCP server on stdin/stdout (see docs/mcp.md).

Declaring the command imports nothing of the SDK; it is imported when the command runs.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from bt_cli.app import App


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser(
        "mcp",
        help="serve the actors and trees as MCP tools over stdio (for language models)",
        description="Run a Model Context Protocol server on stdin/stdout: every actor and tree of the "
        "catalog is a tool (JSON-Schema input, read-only and motion hints), plus "
        "validate_mission, run_mission, show_tree and get_trace. Actors that move the robot "
        "are refused unless motion is allowed (--allow-motion, or mcp: {allow_motion: true} "
        "in actorbt.yaml). See docs/mcp.md for a client configuration.",
    )
    common(p)
    motion = p.add_mutually_exclusive_group()
    motion.add_argument(
        "--allow-motion",
        dest="allow_motion",
        action="store_true",
        default=None,
        help="Run actors and trees that move the robot (default: refused; overrides actorbt.yaml's mcp: allow_motion).",
    )
    motion.add_argument(
        "--no-motion",
        dest="allow_motion",
        action="store_false",
        help="Refuse actors and trees that move the robot, whatever actorbt.yaml says.",
    )
    p.set_defaults(func=cmd_mcp)


def cmd_mcp(args: argparse.Namespace, app: App) -> int:
    from importlib import metadata

    from .server import serve_stdio
    from .service import ToolService
    from .settings import McpSettings
    from .wire import held_wire

    settings = McpSettings.of(app.cfg.mcp, args.allow_motion)
    try:
        version = metadata.version("actorbt")
    except metadata.PackageNotFoundError:
        version = ""
    with held_wire() as wire:  # the world's own prints must not reach the protocol
        rt = app.runtime()
        service = ToolService(rt, settings)
        motion = "allowed" if settings.allow_motion else "off (--allow-motion allows it)"
        print(f"actorbt mcp: {len(service.list_tools())} tools on stdio; motion {motion}", file=sys.stderr)
        try:
            serve_stdio(service, version, wire)
        finally:
            service.close()
            app.close(rt)
    return 0
