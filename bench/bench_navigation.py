"""Base navigation in the simulated house (issue [motion]): 50 random reachable goals,
driven one after another with the `goto` actor. Reports the planning time and the share
of goals reached within 10 cm and 5 degrees.

    .venv/bin/python bench/bench_navigation.py [N]
"""

from __future__ import annotations

import math
import random
import statistics
import sys
import time

from actors.robot import Robot
from bt_engine import ActorError, Runtime
from sim import SimWorld


def main(n: int = 50, seed: int = 1) -> None:
    rng = random.Random(seed)
    with Runtime(watchdog=None) as rt:
        world = SimWorld(rt, world="house", seed=0)
        world.start()
        rt.add_subsystem("robot", Robot)
        nav = rt.root._children["robot"]._children["navigation"]
        reached, plan_ms, errors, failures = 0, [], [], []
        wall0, sim0 = time.perf_counter(), rt.now()
        for i in range(n):
            while True:  # a goal with room for the robot
                gx, gy = rng.uniform(0.3, 9.7), rng.uniform(0.3, 7.7)
                if rt.call("clearance", gx, gy) > 0.35:
                    break
            gyaw = rng.uniform(-math.pi, math.pi)
            try:
                rt.call("goto", gx, gy, gyaw)
            except ActorError as e:
                failures.append(f"goal {i} ({gx:.2f}, {gy:.2f}): {e}")
            path = nav.get_value("last_path")
            if path is not None and path.ok:
                plan_ms.append(path.planning_time * 1000)
            x, y, yaw = world.robot_pose()
            dxy = math.hypot(x - gx, y - gy)
            dyaw = abs(math.degrees(math.remainder(yaw - gyaw, 2 * math.pi)))
            errors.append(dxy)
            if dxy < 0.10 and dyaw < 5.0:
                reached += 1
            print(f"\r{i + 1}/{n} goals, {reached} reached", end="", flush=True)
        wall, sim = time.perf_counter() - wall0, rt.now() - sim0
        rt.run_on_hub(world.close)
    print()
    print(f"goals reached (<10 cm, <5 deg): {reached}/{n} = {100 * reached / n:.0f} %  (target >= 98 %)")
    print(
        f"base planning time: median {statistics.median(plan_ms):.1f} ms, "
        f"max {max(plan_ms):.1f} ms over {len(plan_ms)} plans"
    )
    print(f"final position error: median {1000 * statistics.median(errors):.0f} mm")
    print(f"sim time {sim:.0f} s in {wall:.0f} s wall: {sim / wall:.1f}x real time")
    for f in failures:
        print("  failed:", f)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
