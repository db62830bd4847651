"""Benchmark of the planning library : arm queries, ruckig timing, base planner.

Run:  .venv/bin/python bench/bench_planning.py [--queries 100] [--seed 0]

* Arm: seeded random pick-like queries, from the folded home pose to a
  pre-grasp pose above the floor in front of the robot, among two random
  obstacles on the floor (a box and a can/bottle-sized cylinder). Every query
  has a collision-free IK solution (the generator re-draws until it has).
  Reports success rate, median / p95 planning time and path length before and
  after simplification. Targets: >= 99 % solved, median <= 20 ms, p95 <= 100 ms.
* ruckig: microseconds per rest-to-rest segment (target <= 10 us), raw
  ``Ruckig.calculate`` and through ``time_trajectory``.
* Base: a synthetic house-like grid (rooms, doors, furniture); median planning
  time and share of random goals reached.

The arm queries use the repository URDF; nothing here imports ``sim``.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planning import (  # noqa: E402
    ArmPose,
    GridPlanner,
    JointLimits,
    OccupancyGrid,
    PlanningScene,
    inflate,
    plan_pose_motion,
    seed_planners,
    time_trajectory,
)

HOME = (0.0, -1.0, 0.3, 0.7)  # the simulator's folded "home" [rad]


def pct(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) if values else math.nan


# --------------------------------------------------------------------------- arm
def random_query(scene: PlanningScene, rng: np.random.Generator) -> tuple[ArmPose, bool]:
    """Two obstacles on the floor and a reachable, collision-free pre-grasp pose.

    One obstacle is clutter next to the target (a box 5-15 cm). The other is a
    can/bottle-sized cylinder; in half of the queries it is placed under the
    straight joint-space motion from home, so that motion collides and the
    query needs a real plan. Returns the pose and whether the straight motion
    was blocked on purpose.
    """
    k = scene.kinematics
    block = bool(rng.uniform() < 0.5)
    while True:
        scene.clear()
        pose = ArmPose(
            float(rng.uniform(0.12, 0.32)),
            float(rng.uniform(-0.25, 0.25)),
            float(rng.uniform(0.04, 0.25)),
            float(rng.uniform(0.0, math.pi / 2)),
        )
        ik = k.ik(pose.x, pose.y, pose.z, pose.pitch, seed=HOME)
        if not ik.ok:
            continue
        target = pose.position()
        # clutter next to the target
        while True:
            ang, dist = rng.uniform(-math.pi, math.pi), rng.uniform(0.10, 0.20)
            x, y = target[0] + dist * math.cos(ang), target[1] + dist * math.sin(ang)
            if x > 0.12:
                break
        sx, sy, sz = rng.uniform(0.05, 0.15, 3)
        scene.add_box("clutter", (sx, sy, sz), (x, y, sz / 2))
        if block:
            # a bottle standing under a point of the straight motion to the goal
            goal = np.asarray(ik.solutions[0].q)
            u = rng.uniform(0.3, 0.8)
            tool = k.fk(np.asarray(HOME) + (goal - np.asarray(HOME)) * u)[:3, 3]
            x, y = float(tool[0]), float(tool[1])
            h = float(np.clip(tool[2] + 0.02, 0.10, 0.35))
            if x < 0.11 or math.hypot(x - target[0], y - target[1]) < 0.08:
                continue
        else:
            x, y, h = rng.uniform(0.12, 0.45), rng.uniform(-0.3, 0.3), rng.uniform(0.10, 0.30)
            if math.hypot(x - target[0], y - target[1]) < 0.10:
                continue
        scene.add_cylinder("bottle", float(rng.uniform(0.03, 0.04)), h, (x, y, h / 2))
        if scene.is_valid(HOME) and any(scene.is_valid(s.q) for s in ik.solutions):
            return pose, block


def bench_arm(n: int, seed: int) -> dict[str, float]:
    seed_planners(seed + 1)  # OMPL rejects seed 0
    rng = np.random.default_rng(seed)
    scene = PlanningScene()
    exact = PlanningScene(padding=0.0, acm_samples=0)  # real geometry, to verify the paths
    assert scene.is_valid(HOME), scene.check(HOME).describe()
    plan_pose_motion(HOME, (0.2, 0.0, 0.15, 0.5), scene)  # warm-up (first OMPL use)
    times, raw, simp, planners, failures, ompl_times = [], [], [], {}, [], []
    paths, blocked = [], 0
    for i in range(n):
        pose, block = random_query(scene, rng)
        blocked += block
        result = plan_pose_motion(HOME, pose, scene, timeout=1.0)
        if result.ok:
            times.append(result.planning_time)
            raw.append(result.length_raw)
            simp.append(result.length)
            paths.append(result.path)
            planners[result.planner] = planners.get(result.planner, 0) + 1
            if result.planner != "straight":
                ompl_times.append(result.planning_time)
            exact.clear()
            for ob in scene.obstacles.values():
                if ob.name != "floor":
                    exact.add(ob)
            if not exact.path_valid(result.path, 0.0025, max_step=0.002):
                failures.append(f"query {i}: the path collides with the unpadded obstacles")
        else:
            failures.append(f"query {i}: {result.failure.value}: {result.message}")
    scene.close()
    exact.close()
    ok = len(times)
    print(
        f"arm: {ok}/{n} solved ({100 * ok / n:.1f} %), planners {planners} "
        f"({blocked} queries had an obstacle placed on the straight motion)"
    )
    for f in failures[:5]:
        print("   ", f)
    print(
        f"arm: planning time median {1e3 * statistics.median(times):.2f} ms, "
        f"p95 {1e3 * pct(times, 95):.2f} ms, max {1e3 * max(times):.2f} ms"
    )
    if ompl_times:
        print(
            f"arm: queries that needed OMPL: median {1e3 * statistics.median(ompl_times):.2f} ms, "
            f"p95 {1e3 * pct(ompl_times, 95):.2f} ms"
        )
    print(
        f"arm: path length median {statistics.median(raw):.3f} rad before simplification, "
        f"{statistics.median(simp):.3f} rad after (mean {statistics.mean(raw):.3f} -> {statistics.mean(simp):.3f})"
    )
    return {
        "success": ok / n,
        "median_ms": 1e3 * statistics.median(times),
        "p95_ms": 1e3 * pct(times, 95),
        "paths": paths,  # type: ignore[dict-item]
    }


# ------------------------------------------------------------------------ ruckig
def bench_ruckig(paths: list[tuple[tuple[float, ...], ...]]) -> float:
    from ruckig import InputParameter, Ruckig, Synchronization, Trajectory

    limits = JointLimits((1.5,) * 4, (3.0,) * 4, (30.0,) * 4)
    rng = np.random.default_rng(1)
    pairs = [(rng.uniform(-1.5, 1.5, 4).tolist(), rng.uniform(-1.5, 1.5, 4).tolist()) for _ in range(5000)]
    otg, inp, traj = Ruckig(4), InputParameter(4), Trajectory(4)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = limits.velocity, limits.acceleration, limits.jerk
    inp.synchronization = Synchronization.Phase
    t0 = time.perf_counter()
    for a, b in pairs:
        inp.current_position = a
        inp.target_position = b
        otg.calculate(inp, traj)
    raw_us = (time.perf_counter() - t0) / len(pairs) * 1e6
    segments = sum(len(p) - 1 for p in paths)
    t0 = time.perf_counter()
    reps = 20
    for _ in range(reps):
        for p in paths:
            time_trajectory(p, limits)
    wrapped_us = (time.perf_counter() - t0) / max(1, reps * segments) * 1e6
    print(
        f"ruckig: {raw_us:.2f} us per segment (Ruckig.calculate, Phase sync); "
        f"{wrapped_us:.2f} us per segment through time_trajectory ({segments} segments of the arm paths)"
    )
    return raw_us


# -------------------------------------------------------------------------- base
def house_grid(resolution: float = 0.05) -> OccupancyGrid:
    """A 12 m x 9 m flat: four rooms and a hall, 10 cm walls, 0.9 m doors, furniture."""
    w, h = int(12 / resolution), int(9 / resolution)
    d = np.zeros((h, w), np.int8)

    def box(x0: float, y0: float, x1: float, y1: float, v: int = 100) -> None:
        rows = slice(int(y0 / resolution), int(math.ceil(y1 / resolution)))
        cols = slice(int(x0 / resolution), int(math.ceil(x1 / resolution)))
        d[rows, cols] = v

    t = 0.1
    box(0, 0, 12, t), box(0, 9 - t, 12, 9), box(0, 0, t, 9), box(12 - t, 0, 12, 9)  # outer walls
    box(5, 0, 5 + t, 9), box(0, 4.5, 12, 4.5 + t)  # inner walls: 4 rooms + hall cross
    box(8.5, 0, 8.5 + t, 4.5)
    for x0, y0, x1, y1 in (
        (5, 1.5, 5 + t, 2.4),
        (5, 6.0, 5 + t, 6.9),
        (2.0, 4.5, 2.9, 4.5 + t),
        (9.5, 4.5, 10.4, 4.5 + t),
        (8.5, 2.0, 8.5 + t, 2.9),
        (6.5, 4.5, 7.4, 4.5 + t),
    ):
        box(x0, y0, x1, y1, 0)  # doors
    box(1.0, 1.0, 2.6, 1.8), box(6.0, 6.5, 7.6, 8.0), box(10.0, 6.0, 11.5, 6.8)  # tables, sofa
    box(3.8, 7.8, 4.9, 8.9), box(0.1, 6.0, 0.6, 8.0), box(9.0, 0.5, 9.6, 1.2)  # shelves
    box(11.9, 8.0, 12, 9, -1)  # an unknown corner
    return OccupancyGrid(d, resolution, (0.0, 0.0))


def bench_base(n: int, seed: int) -> dict[str, float]:
    grid = house_grid()
    t0 = time.perf_counter()
    planner = GridPlanner(inflate(grid, robot_radius=0.22))
    build_ms = (time.perf_counter() - t0) * 1e3
    rng = np.random.default_rng(seed)
    free = np.argwhere(~planner.costmap.lethal)
    start = (2.5, 3.0)
    times, reached = [], 0
    for _ in range(n):
        r, c = free[rng.integers(len(free))]
        goal = grid.center_of(int(r), int(c))
        res = planner.plan(start, goal)
        times.append(res.planning_time)
        reached += res.ok
    print(
        f"base: {reached}/{n} goals planned ({100 * reached / n:.0f} %), "
        f"median {1e3 * statistics.median(times):.2f} ms, "
        f"p95 {1e3 * pct(times, 95):.2f} ms per query on a {grid.shape[1]}x{grid.shape[0]} grid "
        f"(costmap + graph built once in {build_ms:.1f} ms)"
    )
    return {"base_median_ms": 1e3 * statistics.median(times), "base_reached": reached / n}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--queries", type=int, default=100, help="arm queries (default 100)")
    ap.add_argument("--goals", type=int, default=50, help="base goals (default 50)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    arm = bench_arm(args.queries, args.seed)
    us = bench_ruckig(arm["paths"])  # type: ignore[arg-type]
    base = bench_base(args.goals, args.seed)
    ok = arm["success"] >= 0.99 and arm["median_ms"] <= 20 and arm["p95_ms"] <= 100 and us <= 10
    print(
        f"summary: arm {100 * arm['success']:.0f} % solved, median {arm['median_ms']:.2f} ms, "
        f"p95 {arm['p95_ms']:.2f} ms; ruckig {us:.2f} us/segment; "
        f"base median {base['base_median_ms']:.2f} ms -> targets {'met' if ok else 'MISSED'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
