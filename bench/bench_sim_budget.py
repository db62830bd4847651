"""Where a simulated second goes: one demo episode (bt_pick_place, house, seed 0 unless
told otherwise), timed per component, as milliseconds of wall time per simulated second,
and the real-time factor of the whole run.

Components are timed by wrapping the functions that do their work (the leaves: nothing
is counted twice); "other" is the rest of the wall time (the engine, the trees, the bus,
the actors' own Python).

    .venv/bin/python bench/bench_sim_budget.py [--world house] [--seed 0] [--category any]
"""

from __future__ import annotations

import argparse
import functools
import importlib
import pathlib
import sys
import time
from collections import defaultdict

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: component: [(module, "Class.method" or "function")]
PARTS = {
    "physics (step, motors, odometry)": [("sim.simworld", "SimWorld.step")],
    "controllers (arm, gripper)": [
        ("sim.controllers", "ArmController.update"),
        ("sim.controllers", "GripperController.update"),
    ],
    "lidar ray casts": [("sim.simworld", "SimWorld.scan_now")],
    "camera render": [("sim.simworld", "SimWorld._render_camera")],
    "robot messages (/tf /odom /imu /joint_states /scan)": [
        ("sim.topics", "SimTopics.tf_msg"),
        ("sim.topics", "SimTopics.odom_msg"),
        ("sim.topics", "SimTopics.imu_msg"),
        ("sim.topics", "SimTopics.joint_state_msg"),
        ("sim.topics", "SimTopics.scan_msg"),
    ],
    "detection": [("actors.perception", "detect")],  # where the actors call it from
    "localiser": [
        ("navstack.localiser", "Localiser._on_scan"),
        ("navstack.localiser", "Localiser._on_odom"),
        ("navstack.localiser", "Localiser._on_imu"),
    ],
    "navigator": [
        ("navstack.navigator", "Navigator._on_scan"),
        ("navstack.navigator", "Navigator._on_tf"),
        ("navstack.navigator", "Navigator._on_depth"),
    ],
    "tf listeners": [("planning.tf_listener", "TfListener._on_tf")],
    "arm planning (OMPL, ruckig)": [
        ("actors.manipulator", "plan_joint_motion"),
        ("actors.manipulator", "plan_pose_motion"),
        ("actors.manipulator", "time_trajectory"),
    ],
}


class Timer:
    """Accumulates the wall time of wrapped calls per component; a call inside another
    timed call is not counted again."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._depth = 0

    def wrap(self, part: str, fn):
        @functools.wraps(fn)
        def timed(*args, **kwargs):
            if self._depth:
                return fn(*args, **kwargs)
            self._depth += 1
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[part] += time.perf_counter() - t0
                self.calls[part] += 1
                self._depth -= 1

        return timed

    def _split_physics(self) -> None:
        """Physics time also by the step's settings (rate, solver iterations), which
        change with what the hand does: still, moving, holding."""
        from sim.simworld import SimWorld

        self.modes: dict[str, list[float]] = defaultdict(lambda: [0.0, 0, 0.0])  # wall, ticks, sim
        step = SimWorld.step

        @functools.wraps(step)
        def step_by_mode(sim):
            iterations = sim.solver_iterations_now  # chosen for this period
            t0 = time.perf_counter()
            step(sim)
            mode = self.modes[f"{sim.physics_hz} Hz, {iterations} solver iterations"]
            mode[0] += time.perf_counter() - t0
            mode[1] += 1
            mode[2] += sim.dt

        SimWorld.step = step_by_mode

    def install(self) -> None:
        self._split_physics()
        for part, targets in PARTS.items():
            for module, name in targets:
                mod = importlib.import_module(module)
                owner, _, attr = name.rpartition(".")
                holder = getattr(mod, owner) if owner else mod
                setattr(holder, attr, self.wrap(part, getattr(holder, attr)))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--world", default="house")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--category", default="any")
    ap.add_argument("--tree", default="bt_pick_place")
    a = ap.parse_args()
    timer = Timer()
    timer.install()
    from demo.episode import run_episode

    t0 = time.perf_counter()
    ep = run_episode(a.tree, a.world, a.seed, category=a.category)
    wall = time.perf_counter() - t0
    sim = ep.sim_time
    print(f"{a.tree} in {a.world} seed {a.seed}: {'success' if ep.success else 'FAILURE: ' + str(ep.reason)}")
    print(
        f"sim {sim:.1f} s, wall {wall:.1f} s: {sim / wall:.1f}x real time "
        "(wall time includes building the world and the runtime)"
    )
    print(f"\n{'component':<52} {'ms per sim s':>12} {'share':>7} {'calls':>8}")
    total = 0.0
    for part in PARTS:
        s = timer.seconds.get(part, 0.0)
        total += s
        print(f"{part:<52} {1000 * s / sim:>12.1f} {s / wall:>7.1%} {timer.calls.get(part, 0):>8}")
    other = max(0.0, wall - total)
    print(f"{'other (engine, trees, bus, actors, start-up)':<52} {1000 * other / sim:>12.1f} {other / wall:>7.1%}")
    print(f"{'all':<52} {1000 * wall / sim:>12.1f} {1.0:>7.1%}")
    print(f"\n{'physics by its settings':<44} {'sim s':>7} {'ms per tick':>12} {'ms per sim s':>12}")
    for mode, (seconds, ticks, sim_s) in sorted(timer.modes.items()):
        print(f"{mode:<44} {sim_s:>7.1f} {1000 * seconds / ticks:>12.2f} {1000 * seconds / sim:>12.1f}")
    return 0 if ep.success else 1


if __name__ == "__main__":
    sys.exit(main())
