"""Search locations: how many of a world's category objects does a survey from them see?

For every seed, the robot is put at each place of a set (moved to the nearest spot with
room for the base, as the search does), turns through the survey's 8 views, and every
view's rendered frame goes through ``detect()`` with the camera's true pose (this
measures where the search looks from, not the localisation). An object counts as seen
when a detection of its category is within 25 cm of it from some place of the set.

The sets: the world's own ``search_locations`` (if it lists any), the places chosen from
the map (``planning.viewpoints``, what a search given no locations visits), and the
world's completed by map places that see the floor they leave unseen (``cover_map``).

    .venv/bin/python bench/bench_search_views.py [--world house_hard] [--seeds 10]
        [--first-seed 2001] [--world-locations house] [--cover COVERAGE:MIN_GAIN ...]

``--cover`` adds rows for the map's places chosen with other ``viewpoints()`` settings.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

from actors.perception import detect, registered_appearances
from bench_perception_hard import _frame, _free, _teleport
from planning.grid import OccupancyGrid, inflate
from planning.viewpoints import viewpoints
from sim import SimWorld
from sim.description import load_world

SEEN = 0.25  # [m] a detection of the category this near the object sees it
VIEWS = 8  # the survey's views per place (actors/search.py)
ROOM = 0.25  # [m] clearance the base needs at a place (search WAYPOINT_CLEARANCE)


def _spot(sim: SimWorld, x: float, y: float) -> tuple[float, float] | None:
    """(x, y), or the nearest spot within 1 m with room for the base (as the search)."""
    if _free(sim, x, y, ROOM):
        return x, y
    for k in range(1, 11):
        for j in range(16):
            a = j * math.pi / 8
            px, py = x + 0.1 * k * math.cos(a), y + 0.1 * k * math.sin(a)
            if _free(sim, px, py, ROOM):
                return px, py
    return None


def _seen(sim: SimWorld, places: list, objects: dict, apps: dict) -> set[str]:
    seen: set[str] = set()
    for place in places:
        spot = _spot(sim, *place)
        if spot is None:
            continue
        for k in range(VIEWS):
            _teleport(sim, spot[0], spot[1], 2 * math.pi * k / VIEWS)
            for d in detect(_frame(sim), apps):
                seen.update(
                    n
                    for n, (cat, ox, oy) in objects.items()
                    if cat == d["category"] and math.dist((d["x"], d["y"]), (ox, oy)) < SEEN
                )
    return seen


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", default="house_hard")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=2001)
    ap.add_argument(
        "--cover",
        nargs="*",
        default=[],
        metavar="COVERAGE:MIN_GAIN",
        help="also the map's places chosen with these viewpoints() settings, e.g. 0.95:0.01 "
        "(the 'map' row is search_views' own)",
    )
    ap.add_argument(
        "--world-locations",
        default="house",
        help="take the hand-made search locations from this world when --world lists none",
    )
    args = ap.parse_args()

    apps = registered_appearances()
    totals: dict[str, list[int]] = {}
    t0 = time.perf_counter()
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        sim = SimWorld(None, args.world, seed=seed)
        try:
            objects = {
                n: (sim.object_category(n), *sim.object_pose(n)[:2])
                for n in sim.object_names()
                if sim.object_category(n) in apps
            }
            given = [
                tuple(p) for p in (sim.spec.search_locations or load_world(args.world_locations, 0).search_locations)
            ]
            g = sim.grid
            costmap = inflate(OccupancyGrid(g.data, g.resolution, tuple(g.origin)), 0.20, inflation_radius=0.45)
            start = tuple(sim.spec.robot_start[:2])
            looked = [s for s in (_spot(sim, *p) for p in given) if s is not None]
            sets = {
                "hand-made": given,
                "map": viewpoints(costmap, start),
                "hand-made + map": given + viewpoints(costmap, start, seen_from=looked),
            }
            for setting in args.cover:
                cover, gain = (float(v) for v in setting.split(":"))
                sets[f"map {setting}"] = viewpoints(costmap, start, coverage=cover, min_gain=gain)
            for label, places in sets.items():
                seen = _seen(sim, places, objects, apps)
                row = totals.setdefault(label, [0, 0, 0])
                row[0] += len(seen)
                row[1] += len(objects)
                row[2] += len(places)
                missed = ", ".join(
                    f"{n} at ({objects[n][1]:.1f}, {objects[n][2]:.1f})" for n in sorted(set(objects) - seen)
                )
                print(
                    f"seed {seed} {label:16s} {len(places):2d} places: {len(seen)}/{len(objects)}"
                    + (f"   missed {missed}" if missed else ""),
                    file=sys.stderr,
                    flush=True,
                )
        finally:
            sim.close()
    print(f"\n{'places':16s} {'per seed':>8s} {'objects seen':>14s}")
    for label, (seen, total, places) in totals.items():
        print(f"{label:16s} {places / args.seeds:8.1f} {seen:>6d}/{total:<4d} {100 * seen / max(1, total):5.1f} %")
    print(f"\n{args.seeds} seeds of {args.world} from {args.first_seed}, {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
