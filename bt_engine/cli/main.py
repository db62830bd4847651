"""The ``actorbt`` command.

Core commands and the tree commands are declared here; ``bt_engine.ros.cli`` and the
plugins named in actorbt.yaml add their own (each module has ``register(subparsers,
common)`` and sets ``func(args, app) -> exit code``). Declaring a command imports nothing
heavy: a command's implementation is imported when it runs, so ``actorbt --help`` and
``actorbt check`` load neither the simulator, ROS nor OpenCV (tests/test_cli_startup.py;
bench/bench_cli_startup.py measures it).
"""
from __future__ import annotations

import argparse
import importlib
import json
import logging
import pprint
import sys
from typing import Callable

from ..errors import ActorbtError
from .app import App
from .config import Config, load_config

#: command modules inside the engine that add sub-commands when importable
BUILTIN_EXTENSIONS = ["bt_engine.ros.cli"]

Command = Callable[[argparse.Namespace, App], int]


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--world", help="world to simulate (overrides actorbt.yaml; 'none': no sim)")
    p.add_argument("--seed", type=int, help="world seed")
    p.add_argument("--gui", action="store_true", help="open pybullet's window (wall clock)")
    p.add_argument("--clock", choices=["virtual", "wall"], help="runtime clock")
    p.add_argument("--ros", action="store_true", help="use the ROS 2 transport")


def _positive_int(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive count, got {text}")
    return n


def _lazy(module: str, name: str) -> Command:
    """The command ``module.name``, imported when it runs (not when the parser is built)."""
    def command(args: argparse.Namespace, app: App) -> int:
        return getattr(importlib.import_module(module), name)(args, app)
    command.__qualname__ = f"{module}.{name}"
    return command


def cmd_list(args: argparse.Namespace, app: App) -> int:
    # from the actor index: the robot's code is neither imported nor constructed
    for e in app.actors_with_trees():
        first = e.doc.splitlines()[0] if e.doc else ""
        print(f"{e.path}{e.shown}  [{'tree' if e.is_tree else e.kind}]  {first}")
    return 0


def cmd_catalog(args: argparse.Namespace, app: App) -> int:
    entries = app.actors_with_trees()
    if args.json:
        print(json.dumps([e.tool for e in entries], indent=2, default=str))
        return 0
    for e in entries:
        print(f"{e.path}{e.shown}  [{'tree' if e.is_tree else e.kind}]")
        for line in e.text_lines():
            print(f"    {line}" if line else "")
    return 0


def cmd_call(args: argparse.Namespace, app: App) -> int:
    stream = getattr(args, "stream", False)
    if getattr(args, "count", None) is not None and not stream:
        raise ActorbtError("--count needs --stream")
    if getattr(args, "ros", False):  # a client of a running `actorbt serve`
        if stream:
            raise ActorbtError("--stream is not available with --ros")
        from ..ros.cli import cmd_rcall
        return cmd_rcall(args, app)
    from ..literals import parse_args
    pos, kw = parse_args(args.args)
    rt = app.runtime()
    try:
        if stream:
            from .shell import INTERRUPTED, stream_actor
            status = stream_actor(rt, args.actor, pos, kw, sys.stdout, as_json=args.json,
                                  count=args.count, timeout=args.timeout)
            if status == INTERRUPTED:
                print("actorbt: interrupted", file=sys.stderr)
            return status
        result = rt.call(args.actor, *pos, timeout=args.timeout, **kw)
    finally:
        app.close(rt)
    if result is not None:
        print(json.dumps(result, default=str) if args.json else pprint.pformat(result))
    return 0


def cmd_shell(args: argparse.Namespace, app: App) -> int:
    from .shell import ActorShell
    rt = app.runtime()
    try:
        ActorShell(rt).cmdloop()
    finally:
        app.close(rt)
    return 0


def build_parser(plugins: list[str]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="actorbt", description=__doc__.splitlines()[0])
    parser.add_argument("--config", help="path of actorbt.yaml (default: nearest one)")
    parser.add_argument("-v", "--verbose", action="count", default=0,
                        help="log more: -v information, -vv debugging (default: warnings only)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("list", help="list actors")
    p.set_defaults(func=cmd_list)

    p = sub.add_parser("catalog", help="describe every actor (--json: JSON-Schema tools)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_catalog)

    p = sub.add_parser("call", help="call one actor: ACTOR ARG... (Python literals, k=v)",
                       description="Call one actor and print its result; with --stream, print "
                                   "every value of a stream as it arrives.")
    p.add_argument("actor")
    p.add_argument("args", nargs="*")
    p.add_argument("--timeout", type=float, metavar="S",
                   help="deadline [s] on the runtime clock (with --stream: end the stream then)")
    p.add_argument("--json", action="store_true", help="print the result (each value) as JSON")
    p.add_argument("--stream", action="store_true",
                   help="print each value, one per line, as it arrives, until the stream ends, "
                        "--count N values, --timeout S or Ctrl-C (exit status 130); a sync or "
                        "async actor is called again for every value (the iterator mode)")
    p.add_argument("--count", type=_positive_int, metavar="N", help="with --stream: stop after N values")
    _common(p)
    p.set_defaults(func=cmd_call)

    p = sub.add_parser("shell", help="interactive actor shell")
    _common(p)
    p.set_defaults(func=cmd_shell)

    _tree_commands(sub)
    for mod_name in BUILTIN_EXTENSIONS + plugins:
        try:
            mod = importlib.import_module(mod_name)
        except ImportError as e:
            if mod_name in BUILTIN_EXTENSIONS and e.name and mod_name.startswith(e.name):
                continue  # that layer is not part of this build
            raise
        mod.register(sub, _common)
    return parser


def _tree_commands(sub: argparse._SubParsersAction) -> None:
    """run, check, show, replay, plot: implemented in bt_engine.trees.cli, which imports
    the whole tree layer (py_trees...), so it is imported only when one of them runs."""
    def tree_command(name: str) -> Command:
        return _lazy("bt_engine.trees.cli", f"cmd_{name}")

    p = sub.add_parser("run", help="run a tree with live progress: TREE [--arg k=v ...]")
    p.add_argument("tree", help="tree name, or a mission file")
    p.add_argument("--arg", action="append", default=[], metavar="NAME=VALUE",
                   help="an input, parsed by its declared type (repeatable)")
    p.add_argument("--record", metavar="FILE.jsonl", help="record a trace for replay and plot")
    p.add_argument("--max-period", type=float, metavar="S", help="tick at least every S seconds")
    p.add_argument("--quiet", action="store_true", help="no progress, only the result")
    p.add_argument("--ticks", action="store_true", help="also print every tick")
    p.add_argument("--json", action="store_true", help="print the outputs as JSON")
    _common(p)
    p.set_defaults(func=tree_command("run"))

    p = sub.add_parser("check", help="validate mission files without running them (default: the trees folder)")
    p.add_argument("files", nargs="*", help="mission YAML files")
    p.set_defaults(func=tree_command("check"))

    p = sub.add_parser("show", help="draw a tree: ASCII here, --out x.png|svg|pdf|dot for a picture")
    p.add_argument("tree", help="tree name, or a mission file")
    p.add_argument("--out", metavar="FILE", help="write a drawing (format from the suffix)")
    p.set_defaults(func=tree_command("show"))

    p = sub.add_parser("replay", help="re-run a recorded tree against its recording; exit 1 on a divergence")
    p.add_argument("trace", help="a .jsonl trace from run --record")
    p.add_argument("--trees", metavar="DIR", help="find the tree files here (default: the recorded paths)")
    p.set_defaults(func=tree_command("replay"))

    p = sub.add_parser("plot", help="draw the timeline of a recorded run")
    p.add_argument("trace", help="a .jsonl trace from run --record")
    p.add_argument("--out", required=True, metavar="FILE.png", help="the picture (png, svg or pdf)")
    p.set_defaults(func=tree_command("plot"))


def _config(argv: list[str]) -> Config | None:
    """actorbt.yaml as ``--config`` names it (the nearest one without), read before the
    full parser exists: the plugins it names add commands. ``None`` if it is broken:
    :class:`App` reports that once the command line is parsed."""
    pre = argparse.ArgumentParser(add_help=False, exit_on_error=False)
    pre.add_argument("--config")
    try:
        known, _ = pre.parse_known_args(argv)
        return load_config(known.config)
    except (argparse.ArgumentError, ActorbtError):
        return None


#: the root log level for no -v, -v and -vv
_LOG_LEVELS = (logging.WARNING, logging.INFO, logging.DEBUG)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    logging.getLogger().setLevel(logging.WARNING)  # basicConfig does nothing when configured
    try:
        cfg = _config(argv)
        parser = build_parser(cfg.plugins if cfg is not None else [])
        args = parser.parse_args(argv)
        logging.getLogger().setLevel(_LOG_LEVELS[min(args.verbose, len(_LOG_LEVELS) - 1)])
        return int(args.func(args, App(args, cfg)) or 0)
    except ActorbtError as e:
        print(f"actorbt: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("actorbt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
