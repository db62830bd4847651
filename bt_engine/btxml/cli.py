"""``actorbt xml import``: BehaviorTree.CPP (or pytwb) XML to mission files.

``bt_engine.cli.main`` declares the arguments and imports this module when the command
runs; each command is ``func(args, app) -> exit status``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..trees._host import STANDARD_BEHAVIOURS
from ..trees._library import TreeLibrary, check_files
from ._api import import_files
from ._emit import write_missions
from ._nodes import NodeModel, read_node_model

__all__ = ["cmd_xml_import"]


def cmd_xml_import(args: argparse.Namespace, app: Any) -> int:
    """Convert the XML files, write one mission per tree into ``--out``, then check the
    written files: against the node model when one is given (the leaves it declares),
    else for structure only (the actors may not exist here)."""
    model: NodeModel | None = read_node_model(args.nodes) if args.nodes else None
    missions = import_files(args.files, model, dialect=args.dialect)
    source = ", ".join(Path(f).name for f in args.files)
    paths = write_missions(missions, args.out, source)
    resolver = model.resolver() if model is not None and len(model) else None
    library = TreeLibrary(resolver, STANDARD_BEHAVIOURS)
    errors = check_files(paths, library=library)
    for path in paths:
        print(f"wrote {path}")
    for error in errors:
        print(error, file=sys.stderr)
    return 1 if errors else 0
