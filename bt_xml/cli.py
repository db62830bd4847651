"""``actorbt xml import|export|btlog``: BehaviorTree.CPP (or pytwb) XML to mission files,
missions to BehaviorTree.CPP XML, and traces to Groot2 logs; and ``actorbt check --nodes``,
which checks missions against a BehaviorTree.CPP node model.

``bt_cli.main`` declares the arguments and imports this module when the command
runs; each command is ``func(args, app) -> exit status``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from bt_engine.errors import ActorbtError
from bt_engine.trees import (
    STANDARD_BEHAVIOURS,
    MissionError,
    TreeLibrary,
    check_files,
    node_plugins,
    read_mission,
    suggest,
)
from bt_tools.cli import cmd_check as check_missions
from bt_tools.cli import unwritten_plugins
from ._api import import_files
from ._emit import write_missions
from ._nodes import NodeModel, read_node_model

__all__ = ["cmd_check", "cmd_xml_btlog", "cmd_xml_export", "cmd_xml_import"]


def cmd_check(args: argparse.Namespace, app: Any) -> int:
    """``actorbt check`` with ``--nodes``: the nodes declared in the node models count as
    actors (their ports give the signatures), before the ones implemented here; their
    controls and decorators that no plugin implements count as plugins still to write."""
    model = read_node_model(args.nodes)
    resolver = model.resolver(app.actor_index().resolve)
    return check_missions(args, app, resolver=resolver, nodes=model.plugins(node_plugins()))


def cmd_xml_import(args: argparse.Namespace, app: Any) -> int:
    """Convert the XML files, write one mission per tree into ``--out``, then check the
    written files: against the node model when one is given (the leaves it declares),
    else for structure only (the actors may not exist here)."""
    model: NodeModel | None = read_node_model(args.nodes) if args.nodes else None
    missions = import_files(args.files, model, dialect=args.dialect)
    source = ", ".join(Path(f).name for f in args.files)
    paths = write_missions(missions, args.out, source)
    resolver = model.resolver() if model is not None and len(model) else None
    nodes = model.plugins(node_plugins()) if model is not None else None
    library = TreeLibrary(resolver, STANDARD_BEHAVIOURS, nodes)
    errors = check_files(paths, library=library)
    for path in paths:
        print(f"wrote {path}")
    for error in errors:
        print(error, file=sys.stderr)
    missing = unwritten_plugins(library, paths)
    if missing and not errors:
        print(f"plugins still to write: {', '.join(missing)} (declared in the node model, used by these trees)")
    return 1 if errors else 0


def _library(args: argparse.Namespace, app: Any) -> tuple[TreeLibrary, str]:
    """The trees folder's trees against the actor catalog (as ``check`` builds them),
    with the mission file ``args.tree`` in place of the folder's tree of its name; and
    the tree's name."""
    library = TreeLibrary(app.actor_index().resolve, STANDARD_BEHAVIOURS)
    given = None
    if args.tree.endswith((".yaml", ".yml")) and Path(args.tree).is_file():
        given = read_mission(args.tree)
    folder = app.cfg.trees_dir()
    if folder is not None and folder.is_dir():
        for path in sorted(folder.glob("*.y*ml")):
            if given is not None and path.resolve() == Path(args.tree).resolve():
                continue
            try:
                mission = read_mission(path)
            except MissionError:
                library.load_file(path, strict=False)  # skipped; asking for it says why
                continue
            if given is None or mission.name != given.name:
                library.add(mission, strict=False)
    if given is not None:
        library.add(given)
        return library, given.name
    if args.tree not in library:
        names = sorted(library.names)
        raise ActorbtError(
            f"unknown tree {args.tree!r}{suggest(args.tree, names)}, expected a tree name "
            f"({', '.join(names) or 'none loaded'}) or a mission file"
        )
    return library, args.tree


def cmd_xml_export(args: argparse.Namespace, app: Any) -> int:
    """Write a tree and the trees it calls as BehaviorTree.CPP v4 XML (with a node model
    from the actor catalog), after checking them as ``actorbt check`` does."""
    from ._export import Exporter, _xml_text

    library, name = _library(args, app)
    exporter = Exporter(library, library.resolver)
    trees = [m.name for m in exporter.trees_of(name)]
    library.check(trees)
    text = _xml_text(exporter.document(name))
    out = Path(args.out)
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ActorbtError(f"cannot write {out}: {exc.strerror or exc}") from None
    actors = sum(1 for m in exporter.models.values() if m.kind != "SubTree")
    print(
        f"wrote {out}: tree {name} with {len(trees) - 1} called tree{'s' if len(trees) != 2 else ''} "
        f"and {actors} actor{'s' if actors != 1 else ''} in its node model"
    )
    return 0


def cmd_xml_btlog(args: argparse.Namespace, app: Any) -> int:
    """Convert a trace to a Groot2 log (BehaviorTree.CPP's FileLogger2 format)."""
    from ._btlog import trace_to_btlog, write_btlog

    xml, first, records = trace_to_btlog(args.trace, trees=args.trees)
    out = write_btlog(args.out, xml, first, records)
    print(f"wrote {out}: {len(records)} transition{'s' if len(records) != 1 else ''}")
    return 0
