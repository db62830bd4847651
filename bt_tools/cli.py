"""The tree layer's ``actorbt`` commands: run, check, show, replay, plot.

``bt_cli.main`` declares their arguments and imports this module when one of
them runs; each command is ``func(args, app) -> exit status``. Errors derive from
ActorbtError, which the main program prints on one line (exit status 2).
"""

from __future__ import annotations

import argparse
import json
import pprint
import sys
import time
from pathlib import Path
from typing import Any, Callable, Mapping

from bt_engine.errors import ActorbtError, ActorError
from bt_engine.runtime import Runtime
from bt_engine.trees import (
    STANDARD_BEHAVIOURS,
    Mission,
    MissionError,
    PluginNode,
    PluginSpec,
    Resolver,
    TreeFailure,
    TreeHost,
    TreeLibrary,
    check_files,
    suggest,
    tree_host,
    walk,
)
from .progress import ProgressPrinter, parse_inputs

__all__ = ["cmd_check", "cmd_plot", "cmd_replay", "cmd_run", "cmd_show"]


def _is_file(spec: str) -> bool:
    return spec.endswith((".yaml", ".yml")) and Path(spec).is_file()


def _mission(host: TreeHost, spec: str) -> Mission:
    """A tree by name, or by file (loaded, validated and registered now)."""
    if _is_file(spec):
        return host.load_file(spec)
    if spec in host.library:
        return host.library[spec]
    names = sorted(host.library.names)
    raise ActorbtError(
        f"unknown tree {spec!r}{suggest(spec, names)}, expected a tree name ({', '.join(names) or 'none loaded'}) "
        "or a mission file"
    )


def cmd_run(
    args: argparse.Namespace, app: Any, *, around: Callable[[Runtime, TreeHost, Mission, dict], Any] | None = None
) -> int:
    """Run a tree; unless ``--quiet``, with live progress and an ending like ``actorbt
    demo``'s: the outcome (outputs once, or where it failed), sim and wall time of the
    run, and the trace file given by ``--record``.

    ``around(rt, host, mission, inputs)``, when given, is called before the run starts
    and returns what watches it (``--bag``, ``--foxglove``): its ``close()`` is called
    once the run ended, and the line its ``summary()`` returns ends the report."""
    rt = app.runtime()
    failure: TreeFailure | None = None
    result: Any = None
    watcher: Any = None
    try:
        host = tree_host(rt, create=True)
        assert host is not None
        if args.max_period is not None:
            host.max_period = args.max_period
        mission = _mission(host, args.tree)
        inputs = parse_inputs(mission, args.arg)
        if not args.quiet:
            host.observers.append(ProgressPrinter(sys.stdout, ticks=args.ticks, outcomes=False))
        recorder = None
        if around is not None:
            watcher = around(rt, host, mission, inputs)
        if args.record:
            from bt_engine.trees import TraceRecorder

            recorder = TraceRecorder(
                args.record, host, tree=mission.name, inputs=inputs, seed=getattr(args, "seed", None)
            )
        sim0, wall0 = rt.now(), time.perf_counter()
        try:
            result = rt.call(mission.name, **inputs)
        except ActorError as exc:
            if not isinstance(exc.__cause__, TreeFailure):
                raise
            failure = exc.__cause__
        finally:
            sim_time, wall_time = rt.now() - sim0, time.perf_counter() - wall0
            if recorder is not None:
                recorder.close()
    finally:
        try:
            if watcher is not None:
                watcher.close()
        finally:
            app.close(rt)
    shown = json.dumps(result, default=str) if args.json else pprint.pformat(result)
    if args.quiet:  # only the result; a failure on stderr
        if failure is not None:
            print(f"actorbt: {failure}", file=sys.stderr)
            return 1
        print(shown)
        return 0
    if failure is None:
        print("SUCCESS" if result is None else f"SUCCESS {shown}")
    else:
        print(f"FAILURE at {failure.node_path}" + (f": {failure.reason}" if failure.reason else ""))
    print(time_line(sim_time, wall_time))
    if args.record:
        print(f"trace:     {args.record}")
    if watcher is not None and watcher.summary():
        print(watcher.summary())
    return 0 if failure is None else 1


def time_line(sim_time: float, wall_time: float) -> str:
    """``sim time 4.0 s, wall time 0.1 s (40.0x real time)``, as ``actorbt demo`` ends."""
    factor = sim_time / wall_time if wall_time > 0 else float("inf")
    return f"sim time {sim_time:.1f} s, wall time {wall_time:.1f} s ({factor:.1f}x real time)"


def cmd_check(
    args: argparse.Namespace,
    app: Any,
    *,
    resolver: Resolver | None = None,
    nodes: Mapping[str, PluginSpec] | None = None,
) -> int:
    """Check mission files against ``resolver``, by default the actor index: not a
    runtime, so no robot code is imported or started (the index is rebuilt, once, when
    that code changed). ``actorbt check --nodes`` passes its own (bt_xml.cli),
    and ``nodes``: the plugins, with the model's controls and decorators still to write."""
    folder = app.cfg.trees_dir()
    files = [Path(f) for f in args.files]
    folder_files = sorted(folder.glob("*.y*ml")) if folder is not None and folder.is_dir() else []
    if not files:
        files = folder_files
    if resolver is None:
        resolver = app.actor_index().resolve
    library = TreeLibrary(resolver, STANDARD_BEHAVIOURS, nodes)
    given = {f.resolve() for f in files}
    for path in folder_files:  # trees the checked files may call
        if path.resolve() not in given:
            try:
                library.load_file(path)
            except MissionError:
                pass  # reported when that file is checked itself
    errors = check_files(files, library=library)
    for error in errors:
        print(error, file=sys.stderr)
    if errors:
        return 1
    print(f"{len(files)} mission file{'s' if len(files) != 1 else ''} OK")
    missing = unwritten_plugins(library, files)
    if missing:
        print(f"plugins still to write: {', '.join(missing)} (declared in the node model, used by these trees)")
    return 0


def unwritten_plugins(library: TreeLibrary, files: list[Path]) -> list[str]:
    """The controls and decorators the missions of ``files`` use that a node model
    declares and no Python class implements yet, as ``Name (kind)``."""
    wanted = {str(f.resolve()) for f in files}
    found: dict[str, str] = {}
    for mission in library:
        if str(Path(mission.file).resolve()) not in wanted:
            continue
        for node in walk(mission.root):
            spec = library.nodes.get(node.plugin) if isinstance(node, PluginNode) else None
            if spec is not None and not spec.implemented:
                found[spec.name] = spec.kind
    return [f"{name} ({kind})" for name, kind in sorted(found.items())]


def _load_for_show(app: Any, spec: str) -> Mission:
    from bt_engine.trees import read_mission

    if _is_file(spec):
        return read_mission(spec)
    library = TreeLibrary()
    folder = app.cfg.trees_dir()
    if folder is not None and folder.is_dir():
        library.load_folder(folder)
    host_like = type("_Lib", (), {"library": library})()
    return _mission(host_like, spec)


def cmd_show(args: argparse.Namespace, app: Any) -> int:
    from .show import ascii_tree, render

    mission = _load_for_show(app, args.tree)
    print(ascii_tree(mission))
    if args.out:
        print(f"wrote {render(mission, args.out)}")
    return 0


def cmd_replay(args: argparse.Namespace, app: Any) -> int:
    from .replay import replay

    report = replay(args.trace, trees=args.trees)
    print(report)
    return 0 if report.ok else 1


def cmd_plot(args: argparse.Namespace, app: Any) -> int:
    from .plot import plot_trace

    print(f"wrote {plot_trace(args.trace, args.out)}")
    return 0
