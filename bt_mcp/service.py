"""The tools of one ``actorbt mcp`` server and what calling each does, without the
SDK: :meth:`ToolService.list_tools` gives MCP tools (wire form), :meth:`ToolService.call`
a ``CallToolResult`` (wire form). ``bt_mcp.server`` connects it to a session.

A call goes: known tool? -> motion allowed? -> arguments fit the schema? -> run.
Nothing runs until all three said yes, so bad input or refused motion moves nothing.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any, Awaitable, Callable, Mapping

import anyio

from bt_engine.actor import ActorRef
from bt_engine.catalog import tool_schema
from bt_engine.errors import ActorbtError
from bt_engine.modes import Kind
from bt_engine.runtime import Runtime
from bt_engine.trees import Mission, MissionError, TreeHost, mission_safety, tree_host
from .calls import CANCEL_GRACE, CallOutcome, run_call
from .mission_tools import MISSION_TOOLS, check_draft, error_entries, errors_text, show_text, trace_result
from .progress import RunWatcher
from .results import error_result, outcome_result, text_result
from .settings import MOTION_HOW_TO, McpSettings
from .tools import mcp_tool
from .validate import argument_errors, call_arguments

__all__ = ["Report", "ToolService"]

#: awaited with each node transition of a running tree: ``{"tree", "path", "status", "depth"}``
Report = Callable[[dict[str, Any]], Awaitable[None]]


@dataclass(frozen=True)
class _Entry:
    ref: ActorRef
    tool: dict[str, Any]  # the catalog's description
    mcp: dict[str, Any]  # as an MCP tool


class ToolService:
    """The catalog of runtime ``rt`` and the mission tools, served under ``settings``."""

    def __init__(self, rt: Runtime, settings: McpSettings) -> None:
        self.rt = rt
        self.settings = settings
        self.host = tree_host(rt, create=True)
        self.watcher = RunWatcher()
        rt.run_on_hub(self.host.observers.append, self.watcher)
        self.last_run: dict[str, Any] | None = None
        self._stopping = 0  # cancelled tree calls not stopped yet
        self._stopped = anyio.Event()
        self._entries = self._catalog()
        self._mission_tools = {t["name"]: t for t in MISSION_TOOLS}
        clash = set(self._entries) & set(self._mission_tools)
        if clash:
            raise ActorbtError(f"actor names {sorted(clash)} are taken by the MCP mission tools")

    def _catalog(self) -> dict[str, _Entry]:
        refs = self.rt.run_on_hub(self.rt.root.all_actors)
        entries = {}
        for ref in sorted(refs, key=lambda r: r.path):
            tool = tool_schema(ref)
            entries[ref.path] = _Entry(
                ref, tool, mcp_tool(tool, ref.signature, allow_motion=self.settings.allow_motion)
            )
        return entries

    def close(self) -> None:
        try:
            self.rt.run_on_hub(self.host.observers.remove, self.watcher)
        except Exception:  # the runtime is already closed
            pass

    # -- listing --------------------------------------------------------------------------
    def list_tools(self) -> list[dict[str, Any]]:
        """Every actor and tree (by path), then the mission tools."""
        return [e.mcp for e in self._entries.values()] + list(self._mission_tools.values())

    def catalog(self) -> list[dict[str, Any]]:
        """The catalog's own descriptions of the actor and tree tools."""
        return [e.tool for e in self._entries.values()]

    # -- calling --------------------------------------------------------------------------
    async def call(self, name: str, arguments: Mapping[str, Any] | None, report: Report) -> dict[str, Any]:
        arguments = dict(arguments or {})
        if name in self._mission_tools:
            problems = argument_errors(self._mission_tools[name]["inputSchema"], arguments)
            if problems:
                return _refused(name, problems)
            return await getattr(self, f"_{name}")(report, **arguments)
        entry = self._entries.get(name)
        if entry is None:
            return error_result(_unknown_tool(name, [*self._entries, *self._mission_tools]))
        if entry.ref.moves and not self.settings.allow_motion:
            return error_result(_motion_refused(f"{name} moves the robot"), {"refused": "motion"})
        problems = argument_errors(entry.mcp["inputSchema"], arguments)
        if problems:
            return _refused(name, problems)
        args, kwargs = call_arguments(entry.ref.signature, arguments)
        try:
            entry.ref.check_args(args, kwargs)
        except ActorbtError as error:
            return _refused(name, [str(error)])
        if not entry.ref.is_tree:
            outcome = await run_call(self.rt, entry.ref, args, kwargs, self.watcher, report)
            return outcome_result(name, outcome, False)
        outcome = await self._run_tree(name, arguments, entry.ref, args, kwargs, report)
        return outcome_result(name, outcome, True)

    async def _run_tree(
        self, shown: str, arguments: dict[str, Any], ref: ActorRef, args: tuple, kwargs: dict, report: Report
    ) -> CallOutcome:
        """A tree call whose trace is kept for ``get_trace``, also when it is cancelled."""
        cancelled = False

        def on_cancel() -> None:
            nonlocal cancelled
            cancelled = True
            self._stopping += 1

        def on_end(outcome: CallOutcome) -> None:
            self._keep_trace(shown, arguments, outcome)
            if cancelled:
                self._stopping -= 1
                if not self._stopping:
                    self._stopped.set()
                    self._stopped = anyio.Event()

        return await run_call(self.rt, ref, args, kwargs, self.watcher, report, on_end, on_cancel)

    def _keep_trace(self, name: str, arguments: dict[str, Any], outcome: CallOutcome) -> None:
        self.last_run = {
            "tool": name,
            "arguments": arguments,
            "events": outcome.trace,
            "dropped": outcome.dropped,
            "outcome": {
                "status": _status(outcome),
                "error": outcome.error,
                "ticks": outcome.ticks,
                "sim_time": round(outcome.sim_time, 3),
            },
        }

    # -- the mission tools (called with their validated arguments) -------------------------
    async def _validate_mission(self, report: Report, yaml: str) -> dict[str, Any]:
        _, errors = await anyio.to_thread.run_sync(check_draft, self.host, yaml)
        if errors:
            return error_result(
                f"{len(errors)} error(s):\n{errors_text(errors)}", {"valid": False, "errors": error_entries(errors)}
            )
        return text_result("valid", {"valid": True, "errors": []})

    async def _run_mission(self, report: Report, yaml: str, inputs: dict | None = None) -> dict[str, Any]:
        mission, errors = await anyio.to_thread.run_sync(check_draft, self.host, yaml)
        if errors or mission is None:
            return error_result(
                f"not run: {len(errors)} error(s):\n{errors_text(errors)}",
                {"valid": False, "errors": error_entries(errors)},
            )
        safety = await anyio.to_thread.run_sync(mission_safety, mission, self.host.library.resolve)
        if safety.moves and not self.settings.allow_motion:
            return error_result(
                _motion_refused(f"mission {mission.name} calls actors that move the robot"), {"refused": "motion"}
            )
        ref = _draft_actor(self.rt, self.host, mission)
        try:
            mission.bind_inputs(**(inputs or {}))
        except ActorbtError as error:
            return _refused("run_mission", [f"inputs: {error}"])
        outcome = await self._run_tree(
            "run_mission", {"mission": mission.name, "inputs": inputs or {}}, ref, (), dict(inputs or {}), report
        )
        return outcome_result(mission.name, outcome, True)

    async def _show_tree(self, report: Report, tree: str | None = None, yaml: str | None = None) -> dict[str, Any]:
        try:
            text = show_text(self.host, tree, yaml)
        except (ActorbtError, MissionError) as error:
            return error_result(str(error))
        return text_result(text, {"text": text})

    async def _get_trace(self, report: Report, limit: int = 500, types: list[str] | None = None) -> dict[str, Any]:
        with anyio.move_on_after(CANCEL_GRACE):  # a run being cancelled is the last run once it stopped
            while self._stopping:
                await self._stopped.wait()
        result = trace_result(self.last_run, limit, types)
        shown = len(result["events"])
        head = (
            f"{result['tool']}: {shown} event(s)" + (f", {result['omitted']} omitted" if result["omitted"] else "")
            if result["tool"]
            else result["note"]
        )
        return text_result(head + "\n" + "\n".join(_event_line(e) for e in result["events"]), result)


def _status(outcome: CallOutcome) -> str:
    if outcome.ok:
        return "SUCCESS"
    return "CANCELLED" if outcome.cancelled else "FAILURE"


def _event_line(event: dict[str, Any]) -> str:
    rest = {k: v for k, v in event.items() if k not in ("t", "type")}
    return f"[{event.get('t', 0):8.2f}] {event.get('type')} {rest}"


def _draft_actor(rt: Runtime, host: TreeHost, mission: Mission) -> ActorRef:
    """The draft as an actor that is not registered (so the tool list stays the catalog)."""

    def run_draft(**inputs: Any) -> dict[str, Any]:
        return host.run_mission(mission, **inputs)

    return ActorRef.build(
        f"run_mission:{mission.name}",
        mission.name,
        run_draft,
        Kind.SYNC,
        owner=rt.root,
        doc=mission.doc or "",
        signature=inspect.Signature([inspect.Parameter("inputs", inspect.Parameter.VAR_KEYWORD)]),
        is_tree=True,
    )


def _motion_refused(what: str) -> str:
    return f"refused: {what}, and this server does not allow motion. To allow it, {MOTION_HOW_TO}."


def _refused(name: str, problems: list[str]) -> dict[str, Any]:
    """Bad arguments: one line per problem, each naming the argument; nothing ran."""
    text = f"{name}: not run, bad arguments:\n" + "\n".join(f"- {p}" for p in problems)
    return error_result(text, {"refused": "arguments", "problems": problems})


def _unknown_tool(name: str, known: list[str]) -> str:
    import difflib

    close = difflib.get_close_matches(name, known, n=3)
    return f"unknown tool {name!r}" + (f"; did you mean {', '.join(map(repr, close))}?" if close else "")
