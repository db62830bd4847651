"""`actorbt map ...`: maps the robot builds, and how good they are (a plugin named in actorbt.yaml).

    actorbt map score BUILT.yaml --world house [--seed 0] [--json]

Each sub-command is one ``_add_<name>(mapsub)`` function that declares its parser and
points ``func`` at its implementation; ``register`` calls each of :data:`SUBCOMMANDS`.
Implementations import their modules when they run, so ``actorbt --help`` stays light.
"""
from __future__ import annotations

import argparse
import json
import math


def _add_score(mapsub) -> None:
    s = mapsub.add_parser(
        "score", help="align a built map to the simulator's truth; precision and recall",
        description="Align a built map_server map to the truth (the simulator's occupancy at "
                    "the lidar's height) by a search over x, y and yaw, then print the "
                    "alignment, the precision (built occupied cells within the tolerance of a "
                    "true one) and the recall (true occupied cells next to free space, the "
                    "faces a lidar sees, within the tolerance of a built one).")
    s.add_argument("built", metavar="BUILT.yaml", help="The built map: a map_server YAML (its PGM beside it).")
    s.add_argument("--world", default="house", metavar="NAME|FILE",
                   help="The world the map was built in: a world's name or its YAML file (default: house).")
    s.add_argument("--seed", type=int, default=0, metavar="N",
                   help="The world's seed (the objects a lidar sees, e.g. a bottle; default: 0).")
    s.add_argument("--locations", metavar="FILE.yaml",
                   help="The locations file of a world built from a map_server map.")
    s.add_argument("--height", type=float, metavar="H",
                   help="The truth's slice above the floor in metres (default: the lidar's height).")
    s.add_argument("--tolerance", type=float, default=0.10, metavar="M",
                   help="How close a cell must be to count as matched, in metres (default: 0.10).")
    s.add_argument("--json", action="store_true", help="Print the figures as one JSON object.")
    s.set_defaults(func=cmd_score)


#: the `map` sub-commands, in the order --help lists them (add `_add_build` here)
SUBCOMMANDS = (_add_score,)


def register(sub, common) -> None:
    p = sub.add_parser("map", help="maps: score a built map against the simulator's truth",
                       description="Maps the robot builds and how good they are.")
    mapsub = p.add_subparsers(dest="map_command", metavar="MAP_COMMAND")
    mapsub.required = True
    for add in SUBCOMMANDS:
        add(mapsub)


def cmd_score(args: argparse.Namespace, app) -> int:
    from sim.gridmap import read_map
    from sim.map_score import score_maps, truth_grid

    built = read_map(args.built).grid
    truth = truth_grid(args.world, args.seed, args.height, args.locations, resolution=built.resolution)
    s = score_maps(built, truth, tolerance=args.tolerance)
    if args.json:
        print(json.dumps({"built": str(args.built), "world": args.world, "seed": args.seed,
                          **s.as_dict()}, indent=2))
        return 0
    a = s.alignment
    print(f"built map {args.built} against {args.world} (seed {args.seed})")
    print(f"alignment: the built map's frame at x {a.x:.3f} m, y {a.y:.3f} m, "
          f"yaw {math.degrees(a.yaw):.2f}° in the world (overlap {a.overlap:.3f})")
    print(f"precision {s.precision:.3f}  ({s.built_occupied} built occupied cells, within "
          f"{s.tolerance * 100:.0f} cm of a true one)")
    print(f"recall    {s.recall:.3f}  ({s.true_faces} true wall-face cells, within "
          f"{s.tolerance * 100:.0f} cm of a built one)")
    return 0
