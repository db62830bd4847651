"""The ``actorbt`` command.

Core commands live here; the tree layer and plugins named in actorbt.yaml add their own
(each module has ``register(subparsers)`` and sets ``func(args, app) -> exit code``).
"""
from __future__ import annotations

import argparse
import importlib
import json
import logging
import pprint
import sys
from typing import Any

from ..errors import ActorbtError
from .app import App
from .config import load_config
from .values import parse_args

#: command modules inside the engine that add sub-commands when importable
BUILTIN_EXTENSIONS = ["bt_engine.trees.cli", "bt_engine.ros.cli"]


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--world", help="world to simulate (overrides actorbt.yaml; 'none': no sim)")
    p.add_argument("--seed", type=int, help="world seed")
    p.add_argument("--gui", action="store_true", help="open pybullet's window (wall clock)")
    p.add_argument("--clock", choices=["virtual", "wall"], help="runtime clock")
    p.add_argument("--ros", action="store_true", help="use the ROS 2 transport")


def cmd_list(args: argparse.Namespace, app: App) -> int:
    rt = app.runtime(with_world=False)
    try:
        for r in sorted(rt.root.all_actors(), key=lambda r: r.path):
            first = r.doc.splitlines()[0] if r.doc else ""
            tag = "tree" if r.is_tree else r.kind.value
            print(f"{r.path}{r.signature}  [{tag}]  {first}")
    finally:
        app.close(rt)
    return 0


def cmd_catalog(args: argparse.Namespace, app: App) -> int:
    from ..catalog import catalog, tool_schemas
    rt = app.runtime(with_world=False)
    try:
        if args.json:
            print(json.dumps(tool_schemas(rt.root), indent=2, default=str))
        else:
            for d in catalog(rt.root):
                print(f"{d['signature']}  [{'tree' if d['is_tree'] else d['kind']}]")
                for line in (d["doc"] or "(no docstring)").splitlines():
                    print(f"    {line}")
    finally:
        app.close(rt)
    return 0


def cmd_call(args: argparse.Namespace, app: App) -> int:
    if getattr(args, "ros", False):  # a client of a running `actorbt serve`
        from ..ros.cli import cmd_rcall
        return cmd_rcall(args, app)
    pos, kw = parse_args(args.args)
    rt = app.runtime()
    try:
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
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("list", help="list actors")
    p.set_defaults(func=cmd_list)

    p = sub.add_parser("catalog", help="describe every actor (--json: JSON-Schema tools)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_catalog)

    p = sub.add_parser("call", help="call one actor: ACTOR ARG... (Python literals, k=v)")
    p.add_argument("actor")
    p.add_argument("args", nargs="*")
    p.add_argument("--timeout", type=float, help="deadline [s] on the runtime clock")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    _common(p)
    p.set_defaults(func=cmd_call)

    p = sub.add_parser("shell", help="interactive actor shell")
    _common(p)
    p.set_defaults(func=cmd_shell)

    for mod_name in BUILTIN_EXTENSIONS + plugins:
        try:
            mod = importlib.import_module(mod_name)
        except ImportError as e:
            if mod_name in BUILTIN_EXTENSIONS and e.name and mod_name.startswith(e.name):
                continue  # that layer is not part of this build
            raise
        mod.register(sub, _common)
    return parser


def _plugins_from_config(argv: list[str]) -> list[str]:
    cfg_path = None
    if "--config" in argv:
        i = argv.index("--config")
        cfg_path = argv[i + 1] if i + 1 < len(argv) else None
    try:
        return load_config(cfg_path).plugins
    except ActorbtError:
        return []


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    try:
        parser = build_parser(_plugins_from_config(argv))
        args = parser.parse_args(argv)
        if args.verbose:
            logging.getLogger().setLevel(logging.DEBUG)
        return int(args.func(args, App(args)) or 0)
    except ActorbtError as e:
        print(f"actorbt: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("actorbt: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
