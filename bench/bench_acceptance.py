"""Issue [speed]: the acceptance in one command, one table. bt_pick_place for can, bottle and
carton over 50 seeds each in house_hard (seeds 2000 on), and bt_tidy_up over 20 seeds, each
episode a fresh world, through `actorbt eval`'s evaluate().

    .venv/bin/python bench/bench_acceptance.py [--seeds N] [--tidy-seeds M] [--categories a,b]
                                               [--jobs J | --ray [ADDRESS]] [--out DIR] [--resume]
        # the full acceptance is 170 episodes: hours with 2 jobs; --seeds 1 --tidy-seeds 1
        # shows the table in minutes. --resume after a cut-off run keeps what it finished.

The table: per category success (n/N, %), objects put where they belong (tidy-up), the
held object's tilt in the hand (median, max), the localisation error (medians of the
episodes' rms and max), sim and wall time per episode (medians), real-time factor, and
the issue's targets (>= 95 % per category, >= 90 % of objects tidied, tilt median <= 5 deg).
CSVs and traces go to --out (default out/acceptance/<category>/, out/acceptance/tidy_up/).
"""

from __future__ import annotations

import argparse
import math
import pathlib
import statistics
import sys
import time
from contextlib import nullcontext

import categories
from demo.episode import Episode
from demo.evaluate import evaluate

CATEGORIES = ("can", "bottle", "carton")
TARGET_PICK = 0.95  # success per category
TARGET_TIDY = 0.90  # objects where they belong
TARGET_TILT = 5.0  # [deg] median tilt of the held object
MAX_FAILED = 20  # failed episodes listed under the table


def _median(xs) -> float:
    xs = [x for x in xs if x == x]
    return statistics.median(xs) if xs else math.nan


def _num(x: float, fmt: str) -> str:
    return "-" if x != x else format(x, fmt)


HEAD = (
    f"{'':12s} {'success':>9s} {'rate':>7s} {'objects placed':>15s} {'tilt med/max deg':>17s} "
    f"{'loc rms/max cm':>15s} {'sim s':>7s} {'wall s':>7s} {'x real':>7s}  target"
)


def row(name: str, eps: list[Episode], tidy: bool = False) -> str:
    n, ok = len(eps), sum(e.success for e in eps)
    rate = ok / n if n else math.nan
    tilts = [e.grasp_tilt_deg for e in eps if e.grasp_tilt_deg == e.grasp_tilt_deg]
    tilt = f"{_num(_median(tilts), '.1f')}/{_num(max(tilts) if tilts else math.nan, '.1f')}"
    loc = (
        f"{_num(100 * _median(e.loc_rmse_m for e in eps), '.1f')}/"
        f"{_num(100 * _median(e.loc_max_m for e in eps), '.1f')}"
    )
    placed = "-"
    if tidy:
        total, done = sum(e.objects or 0 for e in eps), sum(e.placed or 0 for e in eps)
        share = done / total if total else math.nan
        placed = f"{done}/{total} {_num(100 * share, '.0f')}%"
        target = f">= {TARGET_TIDY:.0%} placed: {'ok' if share >= TARGET_TIDY else 'MISSED'}"
    else:
        target = f">= {TARGET_PICK:.0%}: {'ok' if rate >= TARGET_PICK else 'MISSED'}"
        if tilts:
            target += f"; tilt <= {TARGET_TILT:g}: {'ok' if _median(tilts) <= TARGET_TILT else 'MISSED'}"
    return (
        f"{name:12s} {f'{ok}/{n}':>9s} {_num(100 * rate, '6.1f')}% {placed:>15s} {tilt:>17s} "
        f"{loc:>15s} {_num(_median(e.sim_time for e in eps), '7.1f')} "
        f"{_num(_median(e.wall_time for e in eps), '7.1f')} "
        f"{_num(_median(e.realtime_factor for e in eps), '6.1f')}x  {target}"
    )


def table(picks: list[tuple[str, list[Episode]]], tidy: list[Episode] | None, out=sys.stdout) -> None:
    print("\n" + HEAD, file=out)
    for name, eps in picks:
        print(row(name, eps), file=out)
    if len(picks) > 1:
        print(row("all picks", [e for _, eps in picks for e in eps]), file=out)
    if tidy:
        print(row("tidy_up", tidy, tidy=True), file=out)
    failed = [e for _, eps in picks for e in eps if not e.success] + [e for e in tidy or () if not e.success]
    if failed:
        print(f"\nfailed episodes ({len(failed)}; the CSVs have every reason):", file=out)
        for e in failed[:MAX_FAILED]:
            print(f"  {e.tree:13s} seed {e.seed} {e.category:7s} at {e.failed_node or '?'}: {e.reason[:110]}", file=out)
        if len(failed) > MAX_FAILED:
            print(f"  ... and {len(failed) - MAX_FAILED} more", file=out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=50, help="bt_pick_place seeds per category (default 50)")
    ap.add_argument("--tidy-seeds", type=int, default=20, help="bt_tidy_up seeds (default 20; 0: none)")
    ap.add_argument(
        "--categories",
        default=",".join(CATEGORIES),
        help=f"comma-separated (default {','.join(CATEGORIES)}; empty: no pick-and-place)",
    )
    ap.add_argument("--world", default="house_hard")
    ap.add_argument("--first-seed", type=int, default=2000)
    ap.add_argument("--jobs", type=int, default=2, help="episodes at once on this machine (default 2)")
    ap.add_argument(
        "--ray",
        nargs="?",
        const=True,
        default=None,
        metavar="ADDRESS",
        help="run the episodes on Ray instead (see docs/evaluation.md)",
    )
    ap.add_argument("--out", default="out/acceptance", help="CSVs and traces, a folder per row")
    ap.add_argument("--resume", action="store_true", help="keep the episodes --out already has")
    args = ap.parse_args(argv)
    chosen = [c.strip() for c in args.categories.split(",") if c.strip()]
    unknown = [c for c in chosen if c not in categories.names()]
    if unknown:
        ap.error(f"unknown categories {unknown}; registered: {', '.join(categories.names())}")
    out = pathlib.Path(args.out)
    t0 = time.perf_counter()
    picks: list[tuple[str, list[Episode]]] = []
    tidy = None
    if args.ray is not None:  # one Ray for every row (evaluate uses the one running)
        from demo.eval_ray import RayRunner

        cluster = RayRunner(args.ray)
    else:
        cluster = nullcontext()
    how = dict(
        jobs=args.jobs, first_seed=args.first_seed, resume=args.resume, ray=True if args.ray is not None else None
    )
    with cluster:
        for category in chosen:
            print(f"\n--- bt_pick_place, {category}: {args.seeds} seeds in {args.world} ---", flush=True)
            picks.append(
                (category, evaluate("bt_pick_place", args.seeds, args.world, category, out_dir=out / category, **how))
            )
        if args.tidy_seeds:
            print(f"\n--- bt_tidy_up: {args.tidy_seeds} seeds in {args.world} ---", flush=True)
            # the category is not a tidy-up's input: the first registered one names the folder
            tidy = evaluate(
                "bt_tidy_up", args.tidy_seeds, args.world, categories.names()[0], out_dir=out / "tidy_up", **how
            )
    wall = time.perf_counter() - t0
    print(
        f"\nacceptance: bt_pick_place x {args.seeds} seeds per category, bt_tidy_up x {args.tidy_seeds} "
        f"seeds, in {args.world} from seed {args.first_seed}; medians per episode"
    )
    table(picks, tidy)
    where = (
        f"on Ray ({args.ray if isinstance(args.ray, str) else 'ray.init()'})"
        if args.ray is not None
        else f"with {args.jobs} parallel jobs"
    )
    print(f"\ntotal wall time {wall:.0f} s {where}; CSVs in {out}/*/episodes.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
