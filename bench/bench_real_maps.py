"""Pick-and-place on public map_server maps this project did not draw (issue [maps-2]).

Each map under ``sim/maps/`` (its source and licence in ``sim/maps/README.md`` and beside
it) becomes a world (sim/map_world.py), with its authors' ``locations.yaml`` where one
exists; N seeds of bt_pick_place run on it (objects placed from the seed, category mixed:
can and bottle alternate), as ``actorbt eval --world MAP.yaml`` would. Printed per map:
success, localisation error (RMS median, worst), real-time factor, and the failures.

    .venv/bin/python bench/bench_real_maps.py [--seeds 10] [--jobs 2] [--maps tb3_world,...]

Target: success >= 90 % on every map.
"""

from __future__ import annotations

import argparse
import pathlib
import statistics
import sys
import time

from demo.evaluate import evaluate, print_rates, print_table
from sim.description import load_world
from sim.gridmap import read_map

MAPS = pathlib.Path(__file__).resolve().parent.parent / "sim" / "maps"
OUT = pathlib.Path("out/bench_real_maps")
TARGET_RATE = 0.90
FIRST_SEED = 0


def public_maps() -> dict[str, tuple[pathlib.Path, pathlib.Path | None]]:
    """{name: (map YAML, locations YAML or None)} of every map folder under sim/maps/."""
    found = {}
    for folder in sorted(p for p in MAPS.iterdir() if (p / "map.yaml").is_file()):
        locs = folder / "locations.yaml"
        found[folder.name] = (folder / "map.yaml", locs if locs.is_file() else None)
    return found


def describe(name: str, yml: pathlib.Path, locs: pathlib.Path | None) -> None:
    grid = read_map(yml).grid
    spec = load_world(str(yml), FIRST_SEED, str(locs) if locs else None)
    print(
        f"{name}: {yml.relative_to(MAPS.parent.parent)} ({grid.width} x {grid.height} cells at "
        f"{grid.resolution} m) -> {len(spec.walls)} wall boxes, {len(spec.search_locations)} "
        f"search locations, locations file: {locs.name if locs else 'none (chosen from the map)'}",
        flush=True,
    )


def main(argv=None) -> int:
    maps = public_maps()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=FIRST_SEED)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--maps", default=",".join(maps), help="comma-separated: " + ", ".join(maps))
    args = ap.parse_args(argv)
    print(
        "$ "
        + " ".join([".venv/bin/python", "bench/bench_real_maps.py"] + (argv if argv is not None else sys.argv[1:])),
        flush=True,
    )
    names = [n for n in args.maps.split(",") if n]
    for n in names:
        if n not in maps:
            ap.error(f"--maps: unknown map {n!r} (known: {', '.join(maps)})")
    t0 = time.perf_counter()
    rows = []
    for n in names:
        yml, locs = maps[n]
        print(f"\n--- {n}: {args.seeds} seeds ---")
        describe(n, yml, locs)
        eps = evaluate(
            "bt_pick_place",
            args.seeds,
            str(yml),
            "mixed",
            args.jobs,
            OUT / n,
            first_seed=args.first_seed,
            locations=str(locs) if locs else None,
        )
        print_table(eps)
        rows.append((n, eps))
    print_rates(rows, "map", TARGET_RATE)
    print(f"\n{'map':16s} {'loc rms cm (median)':>20s} {'loc max cm (worst)':>19s}")
    for n, eps in rows:
        rms = [e.loc_rmse_m for e in eps if e.loc_rmse_m == e.loc_rmse_m]
        worst = [e.loc_max_m for e in eps if e.loc_max_m == e.loc_max_m]
        print(
            f"{n:16s} {100 * statistics.median(rms) if rms else float('nan'):20.1f} "
            f"{100 * max(worst) if worst else float('nan'):19.1f}"
        )
    print(
        f"\nseeds {args.first_seed}..{args.first_seed + args.seeds - 1}, total wall time "
        f"{time.perf_counter() - t0:.0f} s with {args.jobs} parallel jobs; output in {OUT}/"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
