"""`actorbt demo` and `actorbt eval` (a plugin named in actorbt.yaml)."""

from __future__ import annotations

import pathlib
import sys

from bt_engine.errors import ActorbtError
from bt_ros import LiveOptions, add_live_options


def _world_options(p) -> None:
    """--world, --locations and --no-map, as demo and eval take them."""
    p.add_argument(
        "--world",
        default="house",
        metavar="NAME|FILE",
        help="The world to run in: a world's name or its YAML file (default: house).",
    )
    p.add_argument(
        "--locations",
        metavar="FILE.yaml",
        help="Named places (name: [x, y, theta] per line) for a world built from a map_server map: "
        "'start', 'place' and the places to search.",
    )
    p.add_argument(
        "--no-map",
        action="store_true",
        help="Run the world without its map server: navstack maps it as the robot drives "
        "(for missions that explore first, e.g. bt_map_then_fetch).",
    )


def register(sub, common) -> None:
    p = sub.add_parser(
        "demo",
        help="the reference pick-and-place mission, headless, with pictures",
        description="Run the reference pick-and-place mission once, headless on the "
        "virtual clock, printing its progress; leave its trace, a top view "
        "and a timeline in --out.",
    )
    _world_options(p)
    p.add_argument(
        "--seed", type=int, default=0, metavar="N", help="The world's seed, which places the objects (default: 0)."
    )
    p.add_argument(
        "--category",
        default="any",
        metavar="NAME",
        help="The kind of object to fetch: a registered category (can, bottle, carton, "
        "or one from actorbt.yaml's imports) or any (default: any).",
    )
    p.add_argument("--tree", default="bt_pick_place", help="The mission to run (default: bt_pick_place).")
    p.add_argument(
        "--out", default="out/demo", metavar="DIR", help="The folder for the trace and pictures (default: out/demo)."
    )
    add_live_options(p)
    p.set_defaults(func=cmd_demo)

    e = sub.add_parser(
        "eval",
        help="success rate of a mission over many seeds",
        description="Run a mission once per seed, each in a fresh world, and report "
        "its success rate and times per category, with a CSV of every episode.",
    )
    e.add_argument("tree", help="The mission to evaluate, e.g. bt_pick_place.")
    e.add_argument("--seeds", type=int, default=10, metavar="N", help="How many seeds (episodes) to run (default: 10).")
    e.add_argument(
        "--first-seed", type=int, default=0, metavar="N", help="The first seed; the others follow it (default: 0)."
    )
    _world_options(e)
    e.add_argument(
        "--category",
        default="mixed",
        metavar="NAME",
        help="The kind of object asked for: a registered category (can, bottle, carton, "
        "or one from actorbt.yaml's imports), or mixed: every registered category "
        "in turn (default: mixed).",
    )
    e.add_argument(
        "--jobs",
        type=int,
        default=1,
        metavar="N",
        help="How many episodes run at once on this machine, each in its own process (default: 1).",
    )
    e.add_argument(
        "--out",
        default="out/eval",
        metavar="DIR",
        help="The folder for the traces and episodes.csv, which is rewritten after every episode (default: out/eval).",
    )
    e.add_argument(
        "--resume",
        action="store_true",
        help="Keep the episodes --out's episodes.csv already has (same tree and world) and "
        "run only the missing ones; the CSV gets both.",
    )
    e.add_argument(
        "--ray",
        nargs="?",
        const=True,
        default=None,
        metavar="ADDRESS",
        help="Run the episodes as Ray tasks, one CPU each, instead of --jobs: on the cluster "
        "at ADDRESS (auto, HOST:6379, ray://HOST:10001), else ray.init()'s own choice "
        "(RAY_ADDRESS, a cluster `ray start` started here, or a new local instance). "
        "Needs pip install 'actorbt[cluster]'; see docs/evaluation.md.",
    )
    e.add_argument(
        "--ray-runtime-env",
        metavar="JSON",
        help="Ray's runtime_env for the tasks, as JSON, e.g. "
        '\'{"env_vars": {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}}\'.',
    )
    e.set_defaults(func=cmd_eval)


def _check_category(category: str, wildcard: str) -> None:
    """An unknown category fails before any episode starts, with close matches."""
    if category != wildcard:
        import categories

        categories.get(category)


def _check_world(world: str, seed: int, locations: str | None = None) -> None:
    """A world file's mistakes as one error before any episode starts (not one per episode)."""
    if world == "none":  # the episode says why that cannot run
        return
    from sim import load_world

    load_world(world, seed, locations)


def cmd_demo(args, app) -> int:
    from bt_tools.plot import plot_trace

    from .episode import print_outcome, run_episode

    out = pathlib.Path(args.out)
    _check_category(args.category, "any")
    _check_world(args.world, args.seed, args.locations)
    live = LiveOptions.of(args, app.cfg.robot)
    live.check()
    print(f"actorbt demo: {args.tree} in {args.world} (seed {args.seed}), category {args.category}", flush=True)
    # the runtime is built from actorbt.yaml, as for every command (subsystems, trees, simulator)
    ep = run_episode(
        args.tree,
        args.world,
        args.seed,
        args.category,
        out_dir=out,
        progress=sys.stdout,
        app=app,
        locations=args.locations,
        mapping=args.no_map,
        live=live,
    )
    print_outcome(ep)
    timeline = plot_trace(ep.trace, out / "timeline.png", title=f"{args.tree} (seed {args.seed})")
    print(f"trace:     {ep.trace}\ntop view:  {out / 'top_view.png'}\ntimeline:  {timeline}")
    if live.bag:
        print(f"bag:       {live.bag}")
    return 0 if ep.success else 1


def cmd_eval(args, app) -> int:
    from .evaluate import evaluate, print_table

    _check_category(args.category, "mixed")
    _check_world(args.world, args.first_seed, args.locations)
    runtime_env = None
    if args.ray_runtime_env:
        import json

        try:
            runtime_env = json.loads(args.ray_runtime_env)
        except ValueError as exc:
            raise ActorbtError(f"--ray-runtime-env is not JSON: {exc}") from None
        if args.ray is None:
            raise ActorbtError("--ray-runtime-env needs --ray")
    if args.ray is not None and args.jobs > 1:
        print("--jobs is for one machine: with --ray every CPU of the cluster runs an episode")
    episodes = evaluate(
        args.tree,
        args.seeds,
        args.world,
        args.category,
        args.jobs,
        args.out,
        first_seed=args.first_seed,
        config=app.cfg,
        locations=args.locations,
        mapping=args.no_map,
        resume=args.resume,
        ray=args.ray,
        ray_runtime_env=runtime_env,
    )
    print_table(episodes)
    print(f"\nCSV: {pathlib.Path(args.out) / 'episodes.csv'}")
    return 0 if all(e.success for e in episodes) else 1
