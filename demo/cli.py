"""`actorbt demo` and `actorbt eval` (a plugin named in actorbt.yaml)."""
from __future__ import annotations

import pathlib
import sys


def register(sub, common) -> None:
    p = sub.add_parser("demo", help="the reference pick-and-place mission, headless, with pictures")
    p.add_argument("--world", default="house")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--category", default="any", help="can, bottle or any")
    p.add_argument("--tree", default="bt_pick_place")
    p.add_argument("--out", default="out/demo", help="folder for the trace and pictures")
    p.set_defaults(func=cmd_demo)

    e = sub.add_parser("eval", help="success rate of a mission over many seeds")
    e.add_argument("tree")
    e.add_argument("--seeds", type=int, default=10, help="how many seeds (episodes)")
    e.add_argument("--first-seed", type=int, default=0)
    e.add_argument("--world", default="house")
    e.add_argument("--category", default="mixed", choices=["can", "bottle", "mixed"])
    e.add_argument("--jobs", type=int, default=1, help="episodes run in parallel processes")
    e.add_argument("--out", default="out/eval", help="folder for traces and the CSV")
    e.set_defaults(func=cmd_eval)


def cmd_demo(args, app) -> int:
    from bt_engine.trees import plot_trace

    from .episode import print_outcome, run_episode
    out = pathlib.Path(args.out)
    print(f"actorbt demo: {args.tree} in {args.world} (seed {args.seed}), category {args.category}",
          flush=True)
    # the runtime is built from actorbt.yaml, as for every command (subsystems, trees, simulator)
    ep = run_episode(args.tree, args.world, args.seed, args.category, out_dir=out, progress=sys.stdout,
                     app=app)
    print_outcome(ep)
    timeline = plot_trace(ep.trace, out / "timeline.png", title=f"{args.tree} (seed {args.seed})")
    print(f"trace:     {ep.trace}\ntop view:  {out / 'top_view.png'}\ntimeline:  {timeline}")
    return 0 if ep.success else 1


def cmd_eval(args, app) -> int:
    from .evaluate import evaluate, print_table
    episodes = evaluate(args.tree, args.seeds, args.world, args.category, args.jobs, args.out,
                        first_seed=args.first_seed, config=app.cfg)
    print_table(episodes)
    print(f"\nCSV: {pathlib.Path(args.out) / 'episodes.csv'}")
    return 0 if all(e.success for e in episodes) else 1
