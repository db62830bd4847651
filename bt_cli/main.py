"""The ``actorbt`` command.

Core commands and the tree commands are declared here, ``topic`` in
:mod:`bt_cli.topic`, ``action`` in :mod:`bt_cli.action`;
``bt_ros.cli``, ``bt_ros.pose_cli`` and the
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
import os
import pprint
import sys
from typing import Callable

from bt_engine.errors import ActorbtError
from bt_ros.live_options import LiveOptions, add_live_options
from . import action, topic
from .app import App
from .config import Config, load_config
from .extras import mark_commands, missing_module_message

#: the front-ends' command modules -> the extra their commands need (declaring them imports
#: no third-party package; running one without its extra says what to install)
BUILTIN_EXTENSIONS = {"bt_ros.cli": "ros", "bt_ros.pose_cli": "ros", "bt_mcp.cli": "mcp"}

Command = Callable[[argparse.Namespace, App], int]


def _common(p: argparse.ArgumentParser) -> None:
    """The options of every command that builds a runtime (actors, trees and a world)."""
    p.add_argument(
        "--world",
        metavar="NAME|FILE",
        help="The world to simulate: a world's name or its YAML file; "
        "'none' simulates nothing, so the robot is whatever answers on the bus. "
        "Overrides actorbt.yaml.",
    )
    p.add_argument(
        "--seed",
        type=int,
        metavar="N",
        help="The world's seed: where its objects are placed (the same seed gives the same world).",
    )
    p.add_argument(
        "--locations",
        metavar="FILE",
        help="Named places for the world (name: [x, y, theta] per line), passed to the "
        "simulator: for a world built from a map_server map, where the robot "
        "starts, the place location and the places to search.",
    )
    p.add_argument(
        "--gui",
        action="store_true",
        help="Open pybullet's window to watch the world; the clock is then the wall clock.",
    )
    p.add_argument(
        "--clock",
        choices=["virtual", "wall"],
        help="The runtime's clock: 'virtual' jumps over idle time (fast, deterministic), "
        "'wall' runs in real time. Overrides actorbt.yaml.",
    )
    p.add_argument(
        "--bus",
        choices=["local", "ros"],
        help="Where the robot's topics and actions travel: 'local' inside this process, "
        "'ros' over ROS 2 (DDS), to reach a robot or an `actorbt sim run --bus ros` "
        "in another process. Overrides 'transport:' in actorbt.yaml.",
    )
    p.add_argument("--ros", action=_Renamed, nargs=0, help=argparse.SUPPRESS)


class _Renamed(argparse.Action):
    """``--ros`` meant two things; each has its own name now. Say which."""

    def __call__(self, parser, namespace, values, option_string=None):
        parser.error(
            "--ros is gone: use --bus ros to send the robot's topics over ROS 2, "
            "or `actorbt rcall ACTOR ...` to call an actor of a running `actorbt serve`"
        )


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
    from bt_engine.literals import parse_args

    pos, kw = parse_args(args.args)
    rt = app.runtime()
    try:
        if stream:
            from .shell import INTERRUPTED, stream_actor

            status = stream_actor(
                rt, args.actor, pos, kw, sys.stdout, as_json=args.json, count=args.count, timeout=args.timeout
            )
            if status == INTERRUPTED:
                print("actorbt: interrupted", file=sys.stderr)
            return status
        result = rt.call(args.actor, *pos, timeout=args.timeout, **kw)
    finally:
        app.close(rt)
    if result is not None:
        print(json.dumps(result, default=str) if args.json else pprint.pformat(result))
    return 0


def cmd_run(args: argparse.Namespace, app: App) -> int:
    """``run``, with what --bag and --foxglove add around the run (checked before the
    world is built)."""
    from bt_tools.cli import cmd_run as run_tree

    options = LiveOptions.of(args, app.cfg.robot)
    if not options:
        return run_tree(args, app)
    options.check()
    from bt_ros.live import around_run

    return run_tree(args, app, around=around_run(options, seed=getattr(args, "seed", None)))


def cmd_check(args: argparse.Namespace, app: App) -> int:
    """``check``; with --nodes the XML layer reads the node models (the tree layer does
    not import it) and hands the tree layer's check the actors they declare."""
    module = "bt_xml.cli" if args.nodes else "bt_tools.cli"
    return _lazy(module, "cmd_check")(args, app)


def cmd_shell(args: argparse.Namespace, app: App) -> int:
    from .shell import ActorShell

    rt = app.runtime()
    try:
        ActorShell(rt).cmdloop()
    finally:
        app.close(rt)
    return 0


DESCRIPTION = (
    "Run robot skills (actors) and behaviour-tree missions: call them from the terminal "
    "or a shell, run and check missions, record and replay them, and serve them over ROS 2."
)
EPILOG = (
    "Each command has its own options: `actorbt COMMAND --help`. The command reads the nearest "
    "actorbt.yaml (the subsystems, the trees folder, the world, the bus and the clock)."
)


def _command(sub: argparse._SubParsersAction, name: str, summary: str, description: str) -> argparse.ArgumentParser:
    """A sub-command: ``summary`` in the list of commands, ``description`` in its --help."""
    return sub.add_parser(name, help=summary, description=description)


def build_parser(plugins: list[str]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="actorbt", description=DESCRIPTION, epilog=EPILOG)
    parser.add_argument(
        "--config", metavar="FILE", help="The actorbt.yaml to use (default: the nearest one in this folder or above)."
    )
    parser.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="Log more: -v adds information, -vv debugging (default: warnings only).",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = _command(
        sub,
        "list",
        "list every actor and tree",
        "List every actor and tree with its signature, kind and first line of documentation.",
    )
    p.set_defaults(func=cmd_list)

    p = _command(
        sub,
        "catalog",
        "describe every actor and tree (--json: JSON-Schema tools)",
        "Describe every actor and tree: its documentation and each parameter's description, type, default and unit.",
    )
    p.add_argument(
        "--json",
        action="store_true",
        help="Print the catalog as JSON-Schema tool descriptions, as planners and language models read it.",
    )
    p.set_defaults(func=cmd_catalog)

    p = _command(
        sub,
        "call",
        "call one actor: ACTOR ARG... (Python literals, k=v)",
        "Call one actor in a runtime started here and print its result; with --stream, print "
        "every value of a stream as it arrives. To call an actor of a running `actorbt serve`, "
        "use `actorbt rcall`.",
    )
    p.add_argument("actor", help="The actor's name or path, as `actorbt list` shows it.")
    p.add_argument(
        "args",
        nargs="*",
        metavar="ARG",
        help="Its arguments: Python literals (1, 2.5, 'text', [1, 2]) or NAME=VALUE for keywords; "
        "a word that is no literal is a string.",
    )
    p.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Give up after S seconds on the runtime clock (with --stream: end the stream then).",
    )
    p.add_argument("--json", action="store_true", help="Print the result (with --stream, each value) as JSON.")
    p.add_argument(
        "--stream",
        action="store_true",
        help="Print each value, one per line, as it arrives, until the stream ends, "
        "--count N values, --timeout S or Ctrl-C (exit status 130); a sync or "
        "async actor is called again for every value (the iterator mode).",
    )
    p.add_argument("--count", type=_positive_int, metavar="N", help="With --stream: stop after N values.")
    _common(p)
    p.set_defaults(func=cmd_call)

    p = _command(
        sub,
        "shell",
        "interactive actor shell",
        "An interactive shell in a runtime started here: call actors by name, stream them, "
        "with history, tab completion and `help NAME`.",
    )
    _common(p)
    p.set_defaults(func=cmd_shell)

    _tree_commands(sub)
    for register, extra in [(topic.register, "ros"), (action.register, "ros")]:
        first = len(sub._choices_actions)
        register(sub, _common)
        mark_commands(sub, first, extra)
    for mod_name in list(BUILTIN_EXTENSIONS) + plugins:
        first = len(sub._choices_actions)
        importlib.import_module(mod_name).register(sub, _common)
        if mod_name in BUILTIN_EXTENSIONS:
            mark_commands(sub, first, BUILTIN_EXTENSIONS[mod_name])
    return parser


def _tree_commands(sub: argparse._SubParsersAction) -> None:
    """run, check, show, replay, plot: implemented in bt_tools.cli, which imports
    the whole tree layer (py_trees...), so it is imported only when one of them runs."""

    def tree_command(name: str) -> Command:
        return _lazy("bt_tools.cli", f"cmd_{name}")

    tree_help = "The tree's name (as `actorbt list` shows it) or the path of a mission YAML file."
    trace_help = "A trace (.jsonl) written by `run --record`, `demo`, `eval` or `serve`."
    replay_help = (
        "A trace (.jsonl) written by `run --record`, `demo`, `eval` or `serve`, or a bag "
        "folder written by `run --bag` or `demo --bag`."
    )

    p = _command(
        sub,
        "run",
        "run a tree with live progress: TREE [--arg k=v ...]",
        "Run a mission, printing the active node as it goes, then its outcome, outputs, sim and wall time.",
    )
    p.add_argument("tree", help=tree_help)
    p.add_argument(
        "--arg",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="Set one of the tree's inputs; the value is parsed by the input's declared type. "
        "Repeat it for several inputs.",
    )
    p.add_argument(
        "--record", metavar="FILE.jsonl", help="Record a trace of the run, for `actorbt replay` and `actorbt plot`."
    )
    p.add_argument(
        "--max-period",
        type=float,
        metavar="S",
        help="Tick the tree at least every S seconds, even when no actor call has ended.",
    )
    p.add_argument("--quiet", action="store_true", help="Print no progress, only the outcome.")
    p.add_argument("--ticks", action="store_true", help="Also print a line for every tick.")
    p.add_argument("--json", action="store_true", help="Print the outputs as JSON.")
    add_live_options(p)
    _common(p)
    p.set_defaults(func=cmd_run)

    p = _command(
        sub,
        "check",
        "validate mission files without running them",
        "Validate mission files without running them: YAML, structure, actor names and "
        "arguments, references and expressions. Exit status 1 when any file is broken.",
    )
    p.add_argument(
        "files",
        nargs="*",
        metavar="FILE",
        help="Mission YAML files to check (default: every file of the trees folder).",
    )
    p.add_argument(
        "--nodes",
        action="append",
        default=[],
        metavar="MODEL.xml",
        help="A BehaviorTree.CPP node model (<TreeNodesModel>, a Groot palette) whose Action and "
        "Condition nodes count as actors with the signatures their ports give: check a Nav2 "
        "tree without Nav2. Repeat it for several models.",
    )
    p.set_defaults(func=cmd_check)

    p = _command(
        sub,
        "xml",
        "BehaviorTree.CPP XML: import and export trees, Groot2 logs",
        "Exchange trees with BehaviorTree.CPP v4 (and Groot2, Nav2, pytwb) as XML.",
    )
    xml = p.add_subparsers(dest="xml_command", metavar="ACTION")
    xml.required = True
    p = xml.add_parser(
        "import",
        help="convert XML trees to mission files, one per tree",
        description="Convert BehaviorTree.CPP v4 XML files (with their <include>s) into mission "
        "YAML files, one per <BehaviorTree>, then check them. Errors point at "
        "file.xml:line:column. See docs/btxml.md for what is supported.",
    )
    p.add_argument("files", nargs="+", metavar="FILE.xml", help="The XML files to convert.")
    p.add_argument(
        "--nodes",
        action="append",
        default=[],
        metavar="MODEL.xml",
        help="A node model (<TreeNodesModel>, a Groot palette) declaring the nodes the trees use: "
        "their kind and typed ports. Repeat it for several models.",
    )
    p.add_argument(
        "--dialect",
        choices=["btcpp", "pytwb"],
        default="btcpp",
        help="The XML dialect: btcpp for BehaviorTree.CPP v4 (the default), pytwb for py_trees "
        "workbench XML (py_trees class names, [Python literal] arguments).",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="Where to write the mission files (created).")
    p.set_defaults(func=_lazy("bt_xml.cli", "cmd_xml_import"))
    p = xml.add_parser(
        "export",
        help="write a tree and the trees it calls as BehaviorTree.CPP XML",
        description="Write a tree and every tree it calls as BehaviorTree.CPP v4 XML that Groot2 "
        "opens and edits, with a <TreeNodesModel> built from the actor catalog; "
        "`actorbt xml import` reads it back as the same trees. See docs/btxml.md.",
    )
    p.add_argument(
        "tree", metavar="TREE", help="The tree to export: a tree name of the trees folder, or a mission file."
    )
    p.add_argument("--out", required=True, metavar="F.xml", help="The XML file to write.")
    p.set_defaults(func=_lazy("bt_xml.cli", "cmd_xml_export"))
    p = xml.add_parser(
        "btlog",
        help="convert a trace to a Groot2 log (.btlog)",
        description="Convert a recorded run (a JSONL trace, as run --record writes it) to the log "
        "file BehaviorTree.CPP's FileLogger2 writes, which Groot2 replays. See "
        "docs/btxml.md.",
    )
    p.add_argument("trace", metavar="TRACE.jsonl", help="The trace to convert.")
    p.add_argument("--out", required=True, metavar="F.btlog", help="The Groot2 log file to write.")
    p.add_argument(
        "--trees",
        metavar="DIR",
        help="A folder to find the trace's tree files in by name (default: the paths the trace recorded).",
    )
    p.set_defaults(func=_lazy("bt_xml.cli", "cmd_xml_btlog"))

    p = _command(
        sub,
        "show",
        "draw a tree: ASCII here, --out x.png|svg|pdf|dot for a picture",
        "Draw a mission: as text here, or as a picture with --out.",
    )
    p.add_argument("tree", help=tree_help)
    p.add_argument(
        "--out", metavar="FILE", help="Write a drawing to FILE; its suffix (.png, .svg, .pdf, .dot) gives the format."
    )
    p.set_defaults(func=tree_command("show"))

    p = _command(
        sub,
        "replay",
        "re-run a recorded tree against its recording; exit 1 on a divergence",
        "Run a recorded tree again with every actor call answered from the recording (no robot, "
        "no simulator) and compare what happens; exit status 1 at the first divergence.",
    )
    p.add_argument("trace", help=replay_help)
    p.add_argument(
        "--trees", metavar="DIR", help="Find the tree files in DIR (default: the paths the recording names)."
    )
    p.set_defaults(func=_lazy("bt_ros.bag_replay", "cmd_replay"))

    p = _command(
        sub,
        "plot",
        "draw the timeline of a recorded run",
        "Draw the timeline of a recorded run: each node's running time and each actor call.",
    )
    p.add_argument("trace", help=trace_help)
    p.add_argument(
        "--out",
        required=True,
        metavar="FILE.png",
        help="Where to write the picture; its suffix (.png, .svg, .pdf) gives the format.",
    )
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
    except ModuleNotFoundError as e:
        needs = missing_module_message(e)
        if needs is None:
            raise
        print(f"actorbt: error: this command {needs}", file=sys.stderr)
        return 2
    except ActorbtError as e:
        print(f"actorbt: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("actorbt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (`actorbt catalog --json | head`): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 0


if __name__ == "__main__":
    sys.exit(main())
