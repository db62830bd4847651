"""`actorbt eval`: a mission over many seeds, each in a fresh world, with a table and CSV."""
from __future__ import annotations

import collections
import csv
import multiprocessing
import pathlib
import statistics
import sys
import time
from dataclasses import asdict
from typing import TextIO

import categories
from bt_engine.cli.app import App
from bt_engine.cli.config import Config

from .episode import Episode, episode_app, run_episode

CSV_FIELDS = ["tree", "world", "seed", "category", "success", "tree_status", "failed_node",
              "reason", "placed_object", "pose", "support", "sim_time", "wall_time", "loc_rmse_m", "loc_max_m",
              "grasp_tilt_deg", "pushed", "objects", "placed", "trace"]

#: this process's App (one per worker, so each skipped tree is reported once per process)
_app: App | None = None


def _one(job: tuple) -> Episode:
    global _app
    tree, world, seed, category, out, config, locations, mapping = job
    if _app is None or _app.cfg != config:
        _app = episode_app(world, seed, config=config)
    return run_episode(tree, world, seed, category, out_dir=out, app=_app, locations=locations,
                       mapping=mapping)


def _jobs(tree: str, world: str, seeds: int, first_seed: int, category: str,
          out: pathlib.Path, config: Config | None = None, locations: str | None = None,
          mapping: bool = False) -> list[tuple]:
    cats = categories.names() if category == "mixed" else [category]
    jobs = []
    for i in range(seeds):
        seed = first_seed + i
        # mixed: alternate which category is asked for, so the table shows every strategy
        cat = cats[i % len(cats)]
        jobs.append((tree, world, seed, cat, out / f"{cat}_seed{seed}", config, locations, mapping))
    return jobs


def evaluate(tree: str, seeds: int, world: str = "house", category: str = "mixed",
             jobs: int = 1, out_dir: str | pathlib.Path = "out/eval", first_seed: int = 0,
             progress: TextIO | None = sys.stdout, config: Config | None = None,
             locations: str | None = None, mapping: bool = False) -> list[Episode]:
    """Run ``tree`` for ``seeds`` seeds; returns the episodes in seed order. ``locations``:
    a locations YAML for a world built from a map_server map (see sim/map_world.py);
    ``mapping``: the world has no map server, the robot maps it (see :func:`run_episode`).

    Each episode's runtime is built from ``config`` (actorbt.yaml; by default the
    nearest one), as ``actorbt`` builds every runtime: see :func:`run_episode`.
    """
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if config is None:
        config = episode_app(world, first_seed).cfg
    work = _jobs(tree, world, seeds, first_seed, category, out, config, locations, mapping)
    episodes: list[Episode] = []
    t0 = time.perf_counter()

    def tick() -> None:
        if episodes:   # the CSV so far: a run cut off keeps the episodes it finished
            write_csv(sorted(episodes, key=lambda e: (e.seed, e.category)), out / "episodes.csv")
        if progress is None:
            return
        n, ok = len(episodes), sum(e.success for e in episodes)
        bar = "#" * int(30 * n / len(work))
        progress.write(f"\r[{bar:<30}] {n}/{len(work)} episodes, {ok} succeeded, "
                       f"{time.perf_counter() - t0:.0f} s")
        progress.flush()
    tick()
    try:
        if jobs > 1:
            ctx = multiprocessing.get_context("spawn")  # each worker its own runtime and sim
            with ctx.Pool(jobs) as pool:
                for ep in pool.imap_unordered(_one, work):
                    episodes.append(ep)
                    tick()
        else:
            for job in work:
                episodes.append(_one(job))
                tick()
    finally:  # end the progress line, also when an episode could not start
        if progress is not None:
            progress.write("\n")
    episodes.sort(key=lambda e: (e.seed, e.category))
    write_csv(episodes, out / "episodes.csv")
    return episodes


def write_csv(episodes: list[Episode], path: pathlib.Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, CSV_FIELDS)
        w.writeheader()
        for e in episodes:
            row = {k: v for k, v in asdict(e).items() if k in CSV_FIELDS}
            row["sim_time"] = f"{e.sim_time:.2f}"
            row["wall_time"] = f"{e.wall_time:.2f}"
            row["loc_rmse_m"] = f"{e.loc_rmse_m:.4f}"
            row["loc_max_m"] = f"{e.loc_max_m:.4f}"
            row["grasp_tilt_deg"] = f"{e.grasp_tilt_deg:.1f}"
            row["pushed"] = " ".join(e.pushed)
            w.writerow(row)


def print_table(episodes: list[Episode], out: TextIO = sys.stdout) -> None:
    by_cat: dict[str, list[Episode]] = collections.defaultdict(list)
    for e in episodes:
        by_cat[e.category].append(e)
    out.write(f"\n{'category':10s} {'episodes':>8s} {'success':>8s} {'rate':>7s} "
              f"{'sim s (median)':>15s} {'wall s (median)':>16s} {'x real time':>12s} "
              f"{'loc rms cm':>11s} {'loc max cm':>11s} {'tilt deg':>9s}\n")
    for cat, eps in sorted(by_cat.items()) + [("all", episodes)]:
        ok = sum(e.success for e in eps)
        rms = [e.loc_rmse_m for e in eps if e.loc_rmse_m == e.loc_rmse_m]
        worst = [e.loc_max_m for e in eps if e.loc_max_m == e.loc_max_m]
        tilts = [e.grasp_tilt_deg for e in eps if e.grasp_tilt_deg == e.grasp_tilt_deg]
        out.write(f"{cat:10s} {len(eps):8d} {ok:8d} {100 * ok / len(eps):6.1f}% "
                  f"{statistics.median(e.sim_time for e in eps):15.1f} "
                  f"{statistics.median(e.wall_time for e in eps):16.1f} "
                  f"{statistics.median(e.realtime_factor for e in eps):12.1f} "
                  f"{100 * statistics.median(rms) if rms else float('nan'):11.1f} "
                  f"{100 * max(worst) if worst else float('nan'):11.1f} "
                  f"{statistics.median(tilts) if tilts else float('nan'):9.1f}\n")
    if any(e.pose for e in episodes):
        print_pose_table(episodes, out)
    tidy = [e for e in episodes if e.objects is not None]
    if tidy:
        total, placed = sum(e.objects for e in tidy), sum(e.placed for e in tidy)
        out.write(f"\nobjects where they belong: {placed} of {total} "
                  f"({100 * placed / total if total else float('nan'):.1f}%)\n")
    pushed = [e for e in episodes if e.pushed]
    if pushed:
        out.write(f"\nepisodes in which the robot pushed objects it did not pick: {len(pushed)} of "
                  f"{len(episodes)} ({sum(len(e.pushed) for e in pushed)} objects)\n")
    failures = collections.Counter(e.failed_node or "?" for e in episodes if not e.success)
    if failures:
        out.write("\nfailures by node:\n")
        for node, n in failures.most_common():
            out.write(f"  {n:3d}  {node}\n")
        out.write("\nfailed episodes:\n")
        for e in episodes:
            if not e.success:
                out.write(f"  seed {e.seed:3d} {e.category:7s} {e.failed_node}: {e.reason[:150]}\n")


def print_pose_table(episodes: list[Episode], out: TextIO = sys.stdout) -> None:
    """Successes per category and the pose its object had in the world (the one placed,
    else the one the last pick went for; "none": no pick was tried)."""
    poses = ("upright", "lying", "tilted", "none")
    cells: dict[tuple[str, str], list[bool]] = collections.defaultdict(list)
    for e in episodes:
        cells[e.category, e.pose or "none"].append(e.success)
    out.write(f"\n{'by pose':10s}" + "".join(f"{p:>10s}" for p in poses) + "\n")
    for cat in sorted({e.category for e in episodes}):
        row = [cells.get((cat, p), []) for p in poses]
        out.write(f"{cat:10s}" + "".join(f"{f'{sum(r)}/{len(r)}' if r else '-':>10s}" for r in row) + "\n")


def print_rates(rows: list[tuple[str, list[Episode]]], label: str, target_rate: float,
                target_rtf: float | None = None, out: TextIO = sys.stdout) -> None:
    """One line per (name, episodes): successes, rate, median real-time factor, wall and
    sim time per episode, and the targets met or MISSED (the benchmarks' summary)."""
    print(f"\n{label:8s} {'success':>12s} {'rate':>7s} {'RTF median':>11s} "
          f"{'wall/episode':>13s} {'sim/episode':>12s}", file=out)
    for name, eps in rows:
        n, ok = len(eps), sum(e.success for e in eps)
        rtf = statistics.median(e.realtime_factor for e in eps)
        line = (f"{name:8s} {ok:5d}/{n:<6d} {100 * ok / n:6.1f}% {rtf:10.1f}x "
                f"{statistics.median(e.wall_time for e in eps):11.1f} s "
                f"{statistics.median(e.sim_time for e in eps):10.1f} s   "
                f"target >= {target_rate:.0%}: {'ok' if ok / n >= target_rate else 'MISSED'}")
        if target_rtf is not None:
            line += f"; RTF >= {target_rtf:g}x: {'ok' if rtf >= target_rtf else 'MISSED'}"
        print(line, file=out)
