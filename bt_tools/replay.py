"""Replaying a recorded trace: the tree runs again, every actor call answered from the
recording, with no actors, simulator or ROS. The node statuses and the calls must come
out as recorded; the first event that differs is reported.

Calls to other *trees* are not answered from the recording: those trees run again too,
so an edited subtree is caught as well. Each answered call finishes after the recorded
duration on the virtual clock, with the recorded value or failure; a call that was
cancelled in the recording waits until the replayed tree halts it. The replay ticks with
the recorded host's ``max_period`` and ``behaviour_period`` (header keys; older traces
have none: the defaults).

What is compared (the rule, whichever way the recording was made: ``actorbt run
--record``, a ``serve`` goal, ``TraceRecorder`` around ``rt.call``):

- The events of types :data:`COMPARED`, in order, each on its type and the keys in
  ``_KEYS`` (``log``, ``txn`` and other events are informative only).
- Times are compared **relative to the recorded run's start**: the first compared event
  of the recording is its time zero, and the first event of the replay is the replay's.
  When the recorder was opened (the header's ``start``) does not matter, so a recording
  that began before the tree was started (``serve`` opens it when a goal is accepted,
  and the goal waits for its turn) replays all the same. Reports print these times.
- A recording on the **virtual clock** (header ``clock: virtual``) is deterministic:
  every time must match within :data:`TIME_TOLERANCE` (1 us).
- A recording on the **wall clock** (``clock: wall``: ``serve``, robots) has jitter
  (scheduling, timer latency) that the replay, on the virtual clock, does not: there the
  time *between consecutive compared events* must match within
  ``WALL_TOLERANCE[0] + WALL_TOLERANCE[1] * recorded gap`` (0.2 s + 10 %). Gaps, not
  absolute times, so that latencies do not add up over a long run; a changed ``wait`` or
  ``timeout`` of more than that still shows as a divergence.
"""

from __future__ import annotations

import importlib
import json
import math
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from bt_engine.errors import ActorbtError, Failure
from bt_engine.hub import TimerHandle
from bt_engine.runtime import Runtime
from bt_engine.transaction import Transaction, TxnState
from bt_engine.trees import (
    TRACE_FORMAT,
    TRACE_VERSION,
    CallSite,
    EventBuilder,
    MissionError,
    TreeHost,
    TreeLibrary,
    TreeRun,
    node_plugins,
    read_mission,
)

__all__ = ["Divergence", "ReplayError", "ReplayReport", "describe_event", "locate_trees", "read_trace", "replay"]

#: Event types that must match; ``log`` and ``txn`` events are informative only.
COMPARED = ("run", "tick", "status", "call", "return", "write", "end")
_KEYS = {
    "run": ("run", "tree", "parent"),
    "tick": ("run", "n"),
    "status": ("run", "path", "old", "new"),
    "call": ("run", "path", "call", "actor", "args", "kwargs"),
    "return": ("run", "path", "call", "actor", "state", "value"),
    "write": ("run", "key", "value"),
    "end": ("run", "status", "outputs"),
}
#: Times of a virtual-clock recording must match within this [s].
TIME_TOLERANCE = 1e-6
#: A wall-clock recording: the gap between two compared events may differ by
#: ``absolute + relative * recorded gap`` [s] (see the module docstring).
WALL_TOLERANCE = (0.2, 0.1)


class ReplayError(ActorbtError):
    """A trace cannot be replayed: unreadable, wrong format, or tree files missing."""


class ReplayedError(ActorbtError):
    """The failure a replayed actor call reports: the recorded error text."""


@dataclass(frozen=True)
class Divergence:
    """The first event where the replay differs from the recording (1-based ``index``
    among the compared events); ``None`` on one side means that side had ended."""

    index: int
    expected: dict[str, Any] | None
    got: dict[str, Any] | None

    def __str__(self) -> str:
        return (
            f"first divergence at event {self.index}: expected {describe_event(self.expected)}, "
            f"got {describe_event(self.got)}"
        )


@dataclass
class ReplayReport:
    """What a replay found."""

    tree: str
    compared: int
    divergence: Divergence | None
    notes: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.divergence is None

    def __str__(self) -> str:
        lines = [f"note: {n}" for n in self.notes]
        if self.ok:
            lines.append(f"replay of {self.tree}: OK, {self.compared} events match")
        else:
            lines.append(f"replay of {self.tree}: DIVERGED, {self.divergence}")
        return "\n".join(lines)


def describe_event(event: dict[str, Any] | None) -> str:
    """One line about a trace event, with its time, run and node path."""
    if event is None:
        return "nothing (the run had ended)"
    kind = event.get("type")
    where = f"t={event.get('t', 0):.3f}s run {event.get('run')}"
    if kind == "status":
        what = f"status of {event['path']}: {event['old']} -> {event['new']}"
    elif kind == "call":
        args = [json.dumps(a) for a in event.get("args", [])]
        args += [f"{k}={json.dumps(v)}" for k, v in event.get("kwargs", {}).items()]
        what = f"call #{event['call']} {event['actor']}({', '.join(args)}) by {event['path']}"
    elif kind == "return":
        state = str(event.get("state"))  # as the line shows it (None when missing)
        outcome = {
            "done": f"returned {json.dumps(event.get('value'))}",
            "failed": f"failed ({event.get('error')})",
            "cancelled": f"cancelled ({event.get('reason')})",
        }.get(state, state)
        what = f"call #{event['call']} {event['actor']} {outcome} to {event['path']}"
    elif kind == "tick":
        what = f"tick {event['n']}"
    elif kind == "write":
        what = f"write {event['key']} = {json.dumps(event.get('value'))}"
    elif kind == "run":
        what = f"start of tree {event['tree']}"
    elif kind == "end":
        what = f"end {event['status']}" + (f" {json.dumps(event['outputs'])}" if "outputs" in event else "")
    else:
        what = json.dumps(event)
    return f"[{where}] {what}"


def _same(
    expected: dict[str, Any], got: dict[str, Any], previous: tuple[dict, dict] | None = None, wall: bool = False
) -> bool:
    """Whether ``got`` matches ``expected`` (times relative to the run's start); on the wall
    clock, the gaps since the ``previous`` (expected, got) pair are compared instead."""
    kind = expected.get("type")
    if kind != got.get("type"):
        return False
    t_want, t_got = float(expected.get("t", 0.0)), float(got.get("t", 0.0))
    if wall:
        if previous is not None:
            t_want -= float(previous[0].get("t", 0.0))
            t_got -= float(previous[1].get("t", 0.0))
        absolute, relative = WALL_TOLERANCE
        if abs(t_want - t_got) > absolute + relative * abs(t_want):
            return False
    elif abs(t_want - t_got) > TIME_TOLERANCE:
        return False
    return all(expected.get(k) == got.get(k) for k in _KEYS.get(str(kind), ()))


def read_trace(path: str | Path, lines: list[str] | None = None) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The header and the events of a trace file, event times relative to its start.
    ``lines``: the trace's lines when they were read from elsewhere (a rosbag2 folder's
    /actorbt/trace topic); ``path`` then names them in errors.

    Raises:
        ReplayError: unreadable file, bad JSON, or not an actorbt trace of this version.
    """
    if lines is None:
        try:
            lines = Path(path).read_text(encoding="utf-8").splitlines()
        except OSError as exc:
            raise ReplayError(f"{path}: cannot read trace: {exc.strerror or exc}") from None
    records: list[dict[str, Any]] = []
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ReplayError(f"{path}:{number}:{exc.colno}: not JSON: {exc.msg}") from None
        problem = _record_problem(record, first=not records)
        if problem:
            raise ReplayError(f"{path}:{number}:1: {problem}")
        records.append(record)
    if not records or records[0].get("type") != "header" or records[0].get("format") != TRACE_FORMAT:
        raise ReplayError(f"{path}:1:1: not an actorbt trace, expected a header line with format {TRACE_FORMAT!r}")
    header = records[0]
    if header.get("version") != TRACE_VERSION:
        raise ReplayError(f"{path}:1:1: trace version {header.get('version')}, expected {TRACE_VERSION}")
    problem = _header_problem(header)
    if problem:
        raise ReplayError(f"{path}:1:1: header: {problem}")
    start = float(header.get("start") or 0.0)
    events = records[1:]
    if start:  # times relative to the start of the recording
        events = [{**e, "t": float(e.get("t", start)) - start} for e in events]
    return header, events


#: the keys (and their JSON types) every event of a type must have to be replayed and
#: plotted; the recorder writes more
_EVENT_KEYS: dict[str, dict[str, tuple[type, ...]]] = {
    "run": {"run": (int,), "tree": (str,)},
    "tick": {"run": (int,), "n": (int,)},
    "status": {"run": (int,), "path": (str,), "old": (str,), "new": (str,)},
    "call": {"run": (int,), "path": (str,), "call": (int,), "actor": (str,), "args": (list,), "kwargs": (dict,)},
    "return": {"run": (int,), "path": (str,), "call": (int,), "actor": (str,), "state": (str,)},
    "write": {"run": (int,), "key": (str,)},
    "end": {"run": (int,), "status": (str,)},
}
_JSON_NAMES = {int: "an integer", str: "a string", list: "a list", dict: "an object", float: "a number"}


def _record_problem(record: Any, first: bool) -> str | None:
    """What makes one line of a trace unusable (``None`` if nothing does)."""
    if not isinstance(record, dict):
        return f"expected a JSON object (an event), got {type(record).__name__}"
    kind = record.get("type")
    if first or kind == "header":
        return None  # the header is checked on its own
    if not isinstance(kind, str):
        return "an event without a 'type', expected one of " + ", ".join(["log", "txn", *_EVENT_KEYS])
    t = record.get("t")
    if isinstance(t, bool) or not isinstance(t, (int, float)):
        return f"{kind} event: 't' must be a number (seconds), got {json.dumps(t)}"
    for key, types in _EVENT_KEYS.get(kind, {}).items():
        value = record.get(key)
        if key not in record:
            return f"{kind} event: missing {key!r}"
        if isinstance(value, bool) or not isinstance(value, types):
            return f"{kind} event: {key!r} must be {_JSON_NAMES[types[0]]}, got {json.dumps(value)}"
    return None


def _header_problem(header: dict[str, Any]) -> str | None:
    """What makes a trace's header unusable (``None`` if nothing does)."""
    if not isinstance(header.get("tree"), str):
        return f"'tree' must be the recorded tree's name, got {json.dumps(header.get('tree'))}"
    for key in ("start", "max_period", "behaviour_period"):
        value = header.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))):
            return f"{key!r} must be a number (seconds), got {json.dumps(value)}"
    for key in ("inputs", "trees"):
        if not isinstance(header.get(key) or {}, dict):
            return f"{key!r} must be an object, got {json.dumps(header.get(key))}"
    for name, info in (header.get("trees") or {}).items():
        if not isinstance(info, dict) or not isinstance(info.get("file", ""), str):
            return f"trees[{name!r}] must be an object with 'file' and 'sha256', got {json.dumps(info)}"
    return None


def _from_json(value: Any) -> Any:
    if isinstance(value, dict):
        if set(value) == {"__float__"}:
            return float(value["__float__"])
        return {k: _from_json(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_from_json(v) for v in value]
    return value


class ReplayTxn:
    """Stands in for an actor call's Transaction; ends as the recorded call did."""

    def __init__(
        self, rt: Runtime, number: int, actor: str, call: dict | None, ret: dict | None, on_done: Callable[[Any], None]
    ) -> None:
        self.rt = rt
        self.id = number
        self.path = actor
        self.state = TxnState.RUNNING
        self.result: Any = None
        self.error: BaseException | None = None
        self.reason: str | None = None
        self.kind = (call or {}).get("kind", "sync")
        self._listeners: list[Callable[[ReplayTxn], None]] = [lambda t: on_done(t.outcome())]
        self._timer: TimerHandle | None = None
        if call is None or call.get("actor") != actor:
            recorded = f"call #{number} was {call.get('actor')!r}" if call else f"there is no call #{number}"
            self._timer = rt.call_later(
                0.0, self._finish, TxnState.FAILED, None, ReplayedError(f"not in the recording: {recorded}")
            )
        elif ret is not None and ret.get("state") == "done":
            self._timer = rt.call_later(ret["t"] - call["t"], self._finish, TxnState.DONE, _from_json(ret.get("value")))
        elif ret is not None and ret.get("state") == "failed":
            self._timer = rt.call_later(
                ret["t"] - call["t"], self._finish, TxnState.FAILED, None, ReplayedError(ret.get("error", "failed"))
            )
        # cancelled, or still running when the recording ended: the tree must halt it

    @property
    def done(self) -> bool:
        return self.state is not TxnState.RUNNING

    def outcome(self) -> Any:
        if self.state is TxnState.DONE:
            return self.result
        return Failure(self.error or ReplayedError(self.reason or "cancelled"), self)

    def add_done_callback(self, fn: Callable[[ReplayTxn], None]) -> None:
        if self.done:
            fn(self)
        else:
            self._listeners.append(fn)

    def cancel(self, reason: str = "cancelled") -> None:
        if self.done or self.reason is not None:
            return
        self.reason = reason
        if self.kind == "sync":
            # A sync actor ends when its greenlet next runs and meets Cancelled.
            self.rt.hub.call_soon(self._finish, TxnState.CANCELLED)
        else:
            self._finish(TxnState.CANCELLED)  # async and stream actors: the closer runs at once

    def _finish(self, state: TxnState, result: Any = None, error: BaseException | None = None) -> None:
        if self.done:
            return
        if self._timer is not None:
            self._timer.cancel()
        self.state, self.result, self.error = state, result, error
        listeners, self._listeners = self._listeners, []
        for fn in listeners:
            fn(self)


class ReplayHost(TreeHost):
    """A TreeHost whose actor leaves are answered from recorded calls."""

    def __init__(self, rt: Runtime, calls: dict[int, tuple[dict, dict | None]]) -> None:
        super().__init__(rt)
        self.library = TreeLibrary(None, self.behaviours, self.nodes)  # no actors: structure-only checks
        self.calls = calls
        self._count = 0

    def actor_target(self, name: str) -> tuple[str, str]:
        return name, "sync"  # the kind that matters is the recorded one

    def start_actor(
        self, run: TreeRun, leaf: CallSite, args: tuple, kwargs: dict, on_done: Callable[[Any], None]
    ) -> Any:
        self._count += 1
        if leaf.node.actor in self.library:  # a tree: run it again
            return super().start_actor(run, leaf, args, kwargs, on_done)
        call, ret = self.calls.get(self._count, (None, None))
        return ReplayTxn(self.rt, self._count, leaf.node.actor, call, ret, on_done)


class _Comparer:
    """Compares the replay's events with ``expected`` (times relative to the recorded
    run's start) as they come; the replay's times are made relative to its first event."""

    def __init__(self, expected: list[dict[str, Any]], wall: bool = False) -> None:
        self.expected = list(expected)
        self.wall = wall
        self.got: list[dict[str, Any]] = []
        self.divergence: Divergence | None = None
        self.on_divergence: Callable[[], object] = lambda: None
        self._t0: float | None = None

    def check(self, event: dict[str, Any]) -> None:
        if self._t0 is None:
            self._t0 = float(event.get("t", 0.0))
        event = {**event, "t": float(event.get("t", 0.0)) - self._t0}
        self.got.append(event)
        if self.divergence is not None:
            return
        i = len(self.got) - 1
        want = self.expected[i] if i < len(self.expected) else None
        previous = (self.expected[i - 1], self.got[i - 1]) if i > 0 else None
        if want is not None and not _same(want, event, previous, self.wall):
            self._take_from_batch(i, event, previous)
            want = self.expected[i]
        if want is None or not _same(want, event, previous, self.wall):
            self.divergence = Divergence(i + 1, want, event)
            self.on_divergence()

    def _take_from_batch(self, i: int, event: dict[str, Any], previous: tuple[dict, dict] | None) -> None:
        """The status changes of one tick (consecutive ``status`` events of one run at one
        time) may come in another order than recorded (older recordings told a parent's
        end before its children's): a match later in the batch is moved up to ``i``."""
        first = self.expected[i]
        if first.get("type") != "status" or event.get("type") != "status":
            return
        j = i + 1
        while (
            j < len(self.expected)
            and self.expected[j].get("type") == "status"
            and self.expected[j].get("run") == first.get("run")
            and self.expected[j].get("t") == first.get("t")
        ):
            if _same(self.expected[j], event, previous, self.wall):
                self.expected[i], self.expected[j] = self.expected[j], self.expected[i]
                return
            j += 1

    def finish(self) -> None:
        if self.divergence is None and len(self.got) < len(self.expected):
            self.divergence = Divergence(len(self.got) + 1, self.expected[len(self.got)], None)


def locate_trees(header: dict[str, Any], trace: Path, trees: str | Path | None) -> tuple[dict[str, Path], list[str]]:
    """The tree files of a trace (its ``header``): ``name -> path``, found in the folder
    ``trees`` by tree name, else at the paths the trace recorded (also beside it); and
    a note for each tree changed since the recording. A tree not found: ReplayError."""
    files: dict[str, Path] = {}
    notes: list[str] = []
    by_name: dict[str, Path] = {}
    if trees is not None:
        for path in sorted(Path(trees).glob("*.y*ml")):
            try:
                by_name.setdefault(read_mission(path).name, path)
            except MissionError:
                continue
    for name, info in (header.get("trees") or {}).items():
        recorded = Path(info.get("file", f"{name}.yaml"))
        if trees is not None:
            candidates = [by_name[name]] if name in by_name else []
        else:
            candidates = [recorded, trace.parent / recorded, trace.parent / recorded.name]
        found = next((p for p in candidates if p.is_file()), None)
        if found is None:
            where = f"in {trees}" if trees is not None else f"at {recorded} (recorded path)"
            raise ReplayError(f"{trace}: tree {name!r} not found {where}; pass --trees DIR with the tree files")
        files[name] = found
        current = read_mission(found).source_hash
        if current != info.get("sha256"):
            notes.append(f"tree {name} ({found}) changed since the recording")
    return files, notes


def _import_plugins(header: dict[str, Any], trace: Path) -> None:
    """Import the modules that define the plugin nodes the recording used (the header's
    ``nodes``), unless they are registered already."""
    known = node_plugins()
    for name, module in (header.get("nodes") or {}).items():
        if name in known or not isinstance(module, str):
            continue
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise ReplayError(
                f"{trace}: node {name!r} is defined in module {module!r}, which does not import: {exc}"
            ) from None


def replay(
    trace: str | Path, *, trees: str | Path | None = None, wall_timeout: float = 120.0, lines: list[str] | None = None
) -> ReplayReport:
    """Re-execute a recorded tree run and compare it with the recording.

    Args:
        trace: the ``.jsonl`` file (or where ``lines`` came from: the trees are looked
            for beside it).
        lines: the trace's lines, when not read from ``trace`` (a bag's /actorbt/trace).
        trees: a folder to find the tree files in by name; by default the paths the
            header recorded (relative to the current directory, or the trace's folder).
        wall_timeout: give up after this many real seconds.

    Raises:
        ReplayError: the trace cannot be read or its trees cannot be found.
        MissionError: a tree file no longer loads.
    """
    trace = Path(trace)
    header, events = read_trace(trace, lines)
    expected = [e for e in events if e.get("type") in COMPARED]
    if expected:  # times relative to the recorded run's start (the module docstring)
        t0 = float(expected[0].get("t", 0.0))
        expected = [{**e, "t": float(e.get("t", t0)) - t0} for e in expected]
    wall = header.get("clock") == "wall"
    tree = header["tree"]
    files, notes = locate_trees(header, trace, trees)
    calls: dict[int, tuple[dict, dict | None]] = {}
    returns = {e["call"]: e for e in expected if e["type"] == "return"}
    for e in expected:
        if e["type"] == "call":
            calls[e["call"]] = (e, returns.get(e["call"]))
    comparer = _Comparer(expected, wall=wall)
    _import_plugins(header, trace)
    with Runtime(clock="virtual") as rt:
        host = ReplayHost(rt, calls)
        if header.get("max_period") is not None:
            host.max_period = float(header["max_period"])
        if header.get("behaviour_period") is not None:
            host.behaviour_period = float(header["behaviour_period"])
        for path in files.values():
            host.library.load_file(path)
        host.library.check()
        for mission in host.library:
            host.register(mission)
        host.observers.append(EventBuilder(comparer.check))
        finished = threading.Event()
        end = expected[-1]["t"] if expected else 0.0
        limit = end + 1.0 + (WALL_TOLERANCE[0] * len(expected) + WALL_TOLERANCE[1] * end if wall else 0.0)
        inputs = _from_json(header.get("inputs") or {})

        def start() -> Transaction:
            txn = rt.start(tree, on_done=lambda _: finished.set(), **inputs)
            comparer.on_divergence = lambda: rt.call_later(0.0, txn.cancel, "replay diverged from the recording")
            rt.call_later(limit, txn.cancel, "replay ran past the end of the recording")
            return txn

        rt.run_on_hub(start)
        if not finished.wait(wall_timeout):
            notes.append(f"the replay did not finish within {wall_timeout:g} s of real time")
            if comparer.divergence is None:
                comparer.divergence = Divergence(len(comparer.got) + 1, None, None)
        rt.run_on_hub(lambda: None)  # let the last events land
        comparer.finish()
    if not math.isfinite(limit):  # pragma: no cover - defensive
        notes.append("the recording has no end time")
    return ReplayReport(tree, len(expected), comparer.divergence, notes)
