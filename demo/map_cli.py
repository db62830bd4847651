"""`actorbt map ...`: maps the robot builds, and how good they are (a plugin named in actorbt.yaml).

    actorbt map build --world house [--seed 0] --out DIR [--max-time S]
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
        "score",
        help="align a built map to the simulator's truth; precision and recall",
        description="Align a built map_server map to the truth (the simulator's occupancy at "
        "the lidar's height) by a search over x, y and yaw, then print the "
        "alignment, the precision (built occupied cells within the tolerance of a "
        "true one) and the recall (true occupied cells next to free space, the "
        "faces a lidar sees, within the tolerance of a built one).",
    )
    s.add_argument("built", metavar="BUILT.yaml", help="The built map: a map_server YAML (its PGM beside it).")
    s.add_argument(
        "--world",
        default="house",
        metavar="NAME|FILE",
        help="The world the map was built in: a world's name or its YAML file (default: house).",
    )
    s.add_argument(
        "--seed",
        type=int,
        default=0,
        metavar="N",
        help="The world's seed (the objects a lidar sees, e.g. a bottle; default: 0).",
    )
    s.add_argument(
        "--locations", metavar="FILE.yaml", help="The locations file of a world built from a map_server map."
    )
    s.add_argument(
        "--height",
        type=float,
        metavar="H",
        help="The truth's slice above the floor in metres (default: the lidar's height).",
    )
    s.add_argument(
        "--tolerance",
        type=float,
        default=0.10,
        metavar="M",
        help="How close a cell must be to count as matched, in metres (default: 0.10).",
    )
    s.add_argument("--json", action="store_true", help="Print the figures as one JSON object.")
    s.add_argument(
        "--png",
        metavar="FILE.png",
        help="Also draw the built map on the truth: matched cells green, cells off "
        "the truth red, true wall faces missed blue.",
    )
    s.set_defaults(func=cmd_score)


def _add_build(mapsub) -> None:
    b = mapsub.add_parser(
        "build",
        help="the robot explores a world with no map and builds one from /scan and /odom",
        description="Run the world without its map server; the robot explores to the frontiers "
        "of what it has mapped so far (navstack's mapper: scan matching, log-odds "
        "grid, loop closure) until none is left, then writes the map as map_server "
        "YAML + PGM (5 cm cells, trinary). Prints the trajectory error against the "
        "simulator's truth.",
    )
    b.add_argument(
        "--world",
        default="house",
        metavar="NAME|FILE",
        help="The world to explore: a world's name or its YAML file (default: house).",
    )
    b.add_argument("--seed", type=int, default=0, metavar="N", help="The world's seed (default: 0).")
    b.add_argument(
        "--locations", metavar="FILE.yaml", help="The locations file of a world built from a map_server map."
    )
    b.add_argument(
        "--out", default="out/map", metavar="DIR", help="Where to write map.yaml and map.pgm (default: out/map)."
    )
    b.add_argument(
        "--max-time",
        type=float,
        default=900.0,
        metavar="S",
        help="Give up exploring after this many simulated seconds (default: 900).",
    )
    b.set_defaults(func=cmd_build)


#: the `map` sub-commands, in the order --help lists them
SUBCOMMANDS = (_add_build, _add_score)


def register(sub, common) -> None:
    p = sub.add_parser(
        "map",
        help="maps: build one by exploring, score it against the simulator's truth",
        description="Maps the robot builds and how good they are.",
    )
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
    if args.png:
        import cv2

        from sim.map_score import overlay_image

        if not cv2.imwrite(args.png, overlay_image(built, truth, s)[..., ::-1]):
            raise SystemExit(f"actorbt map score: cannot write {args.png}")
    if args.json:
        print(json.dumps({"built": str(args.built), "world": args.world, "seed": args.seed, **s.as_dict()}, indent=2))
        return 0
    a = s.alignment
    print(f"built map {args.built} against {args.world} (seed {args.seed})")
    print(
        f"alignment: the built map's frame at x {a.x:.3f} m, y {a.y:.3f} m, "
        f"yaw {math.degrees(a.yaw):.2f}° in the world (overlap {a.overlap:.3f})"
    )
    print(
        f"precision {s.precision:.3f}  ({s.built_occupied} built occupied cells, within "
        f"{s.tolerance * 100:.0f} cm of a true one)"
    )
    print(
        f"recall    {s.recall:.3f}  ({s.true_faces} true wall-face cells, within "
        f"{s.tolerance * 100:.0f} cm of a built one)"
    )
    return 0


def cmd_build(args: argparse.Namespace, app) -> int:
    import logging
    import sys

    from demo.mapping import build_map

    # progress: each frontier the robot drives to (the run takes minutes)
    log = logging.getLogger("actors.exploration")
    handler = logging.StreamHandler(sys.stdout)
    handler.setFormatter(logging.Formatter("  %(message)s"))
    log.addHandler(handler)
    log.setLevel(logging.INFO)
    log.propagate = False

    print(f"actorbt map build: exploring {args.world} (seed {args.seed}) with no map", flush=True)
    run = build_map(
        args.world, args.seed, args.out, locations=args.locations, max_time=args.max_time, progress=sys.stdout
    )
    m = run.mapping
    if run.map_yaml:
        print(
            f"map:        {run.map_yaml} ({m.get('width')} x {m.get('height')} cells of "
            f"{m.get('resolution')} m; {m.get('keyframes')} keyframes, "
            f"{m.get('loop_closures')} loop closures, {m.get('travelled')} m travelled)"
        )
    print(f"sim time {run.sim_time:.1f} s, wall time {run.wall_time:.1f} s")
    print(f"trajectory error: {run.traj_rmse_m * 100:.1f} cm rms, {run.traj_max_m * 100:.1f} cm max")
    if not run.success:
        print(f"exploration did not finish: {run.reason}", file=sys.stderr)
        return 1
    return 0
