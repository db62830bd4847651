"""Pick-and-place on worlds built from map_server maps (issue [maps] item 3, sim/map_world.py):
the success rate of bt_pick_place over N seeds, the median wall time per episode and the
real-time factor, on two maps:

* ``house``: the house's own map as ``actorbt sim map --world house --height`` exports it
  (the slice at the lidar's height, 0.132 m: walls, furniture, the standing objects of
  house seed 0), with a locations file naming the house's start, its search locations (by
  room) and its place location;
* ``slam``: the same map made to look like a real gmapping / slam_toolbox map by
  :func:`sim.map_degrade.slam_like` from a fixed seed: turned 3° with a non-zero origin,
  only what a lidar driven through the places saw is known (unknown behind furniture and
  inside walls), walls one cell thin and ragged with 1-cell gaps and rays leaking out,
  occupied speckles and unknown patches in the floor; its locations file is the same
  places in its frame.

Each episode is ``demo.evaluate.evaluate`` on ``--world MAP.yaml --locations LOCS.yaml``
(as ``actorbt eval``), a fresh map-built world per seed (objects placed from the seed near
the search locations), category mixed (can and bottle alternate). Maps, locations files,
traces, top views and a CSV per map go to out/bench_map_world/.

    .venv/bin/python bench/bench_map_world.py [--seeds 20] [--jobs 2] [--maps house,slam]
        # the defaults took 29 minutes on two cores shared with another job (the SLAM-like
        # world's 570 wall bodies make its episodes ~1.6x slower than the house export's)

Target: success >= 90 % on each map.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import time

from demo.evaluate import evaluate, print_rates, print_table
from sim import write_map
from sim.description import load_world
from sim.gridmap import lidar_height, read_map
from sim.map_degrade import write_slam_like
from sim.map_world import write_locations

OUT = pathlib.Path("out/bench_map_world")
TARGET_RATE = 0.90
FIRST_SEED = 2000
DEGRADE_SEED = 7  # the SLAM-like map is one fixed map (a user's map does not change)
ROTATION = math.radians(3.0)


def house_places() -> dict:
    """The house's start, search locations (named by room) and place location, in order."""
    spec = load_world("house", 0)
    places = {"start": tuple(spec.robot_start)}
    for x, y in spec.search_locations:
        room = spec.room_of(x, y) or "spot"
        name, k = room, 2
        while name in places:
            name, k = f"{room}_{k}", k + 1
        places[name] = (x, y)
    places["place"] = (spec.place.x, spec.place.y, spec.place.yaw)
    return places


def make_maps(out: pathlib.Path) -> dict:
    """{name: (map YAML, locations YAML, note)} of the two maps, written under ``out``."""
    places = house_places()
    _, house_yaml = write_map("house", 0, out / "house.pgm", height=lidar_height())
    house_locs = write_locations(out / "house_locations.yaml", places)
    slam_yaml, slam_locs, m = write_slam_like(house_yaml, out / "slam.pgm", places, DEGRADE_SEED, ROTATION)
    note = (
        f"turned {math.degrees(ROTATION):g} deg, origin ({m.grid.origin[0]:g}, {m.grid.origin[1]:g}), "
        f"{len(m.gaps)} 1-cell gaps, {len(m.speckles)} speckles, {len(m.patches)} unknown patches"
    )
    return {
        "house": (house_yaml, house_locs, "the house's export at the lidar's height"),
        "slam": (slam_yaml, slam_locs, note),
    }


def describe(name: str, yml: pathlib.Path, locs: pathlib.Path, note: str) -> None:
    grid = read_map(yml).grid
    spec = load_world(str(yml), FIRST_SEED, str(locs))
    occupied = int((grid.data == 100).sum())
    print(
        f"{name}: {yml} ({grid.width} x {grid.height} cells at {grid.resolution} m, "
        f"{occupied} occupied) -> {len(spec.walls)} wall boxes, "
        f"{len(spec.search_locations)} search locations; {note}",
        flush=True,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--maps", default="house,slam", help="comma-separated: house, slam")
    args = ap.parse_args(argv)
    print(
        "$ "
        + " ".join([".venv/bin/python", "bench/bench_map_world.py"] + (argv if argv is not None else sys.argv[1:])),
        flush=True,
    )
    names = [n for n in args.maps.split(",") if n]
    for n in names:
        if n not in ("house", "slam"):
            ap.error(f"--maps: unknown map {n!r} (house, slam)")
    maps = make_maps(OUT)
    t0 = time.perf_counter()
    rows = []
    for n in names:
        yml, locs, note = maps[n]
        print(f"\n--- {n}: {args.seeds} seeds ---")
        describe(n, yml, locs, note)
        eps = evaluate(
            "bt_pick_place",
            args.seeds,
            str(yml),
            "mixed",
            args.jobs,
            OUT / n,
            first_seed=FIRST_SEED,
            locations=str(locs),
        )
        print_table(eps)
        rows.append((n, eps))
    print_rates(rows, "map", TARGET_RATE)
    print(
        f"\nseeds {FIRST_SEED}..{FIRST_SEED + args.seeds - 1}, total wall time "
        f"{time.perf_counter() - t0:.0f} s with {args.jobs} parallel jobs; output in {OUT}/"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
