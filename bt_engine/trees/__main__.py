"""``python -m bt_engine.trees FILE...``: validate mission files without an engine.

Checks structure and blackboard data flow; with ``--fake-actors`` also actor names and
signatures against the test catalogue of :func:`bt_engine.trees.testing.demo_resolver`.
``actorbt check`` does the same against the configured runtime. Exit status 1 on an error.
"""

from __future__ import annotations

import argparse
import sys

from ._library import check_files
from .testing import DEMO_BEHAVIOURS, demo_resolver


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bt_engine.trees", description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+", help="mission YAML files")
    parser.add_argument("--fake-actors", action="store_true", help="resolve actors against the test catalogue")
    args = parser.parse_args(argv)
    if args.fake_actors:
        errors = check_files(args.files, demo_resolver(), behaviours=DEMO_BEHAVIOURS)
    else:
        errors = check_files(args.files)
    for error in errors:
        print(error, file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
