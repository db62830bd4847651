"""Simulator real-time factor under the virtual clock on `house` (issue [sim]).

Three cases: no camera subscriber; camera 320x240 at 5 Hz; camera 640x480 at 5 Hz. The
robot drives a slow arc and the arm moves, so the physics has contacts to solve. Each case
runs REPEATS times for SIM_SECONDS of simulated time; medians are printed.
Targets: >= 15x real time with the camera off, >= 4x at 320x240 and 5 Hz.

    .venv/bin/python bench/bench_sim.py
"""

from __future__ import annotations

import statistics
import sys
import time

from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image, JointState

from bt_engine import Runtime
from sim import SimWorld
from sim.topics import CMD_VEL

SIM_SECONDS = 10.0
REPEATS = 3
CASES = [("camera off", None), ("camera 320x240 @ 5 Hz", (320, 240)), ("camera 640x480 @ 5 Hz", (640, 480))]
TARGETS = {"camera off": 15.0, "camera 320x240 @ 5 Hz": 4.0}


def run_case(size):
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "house", seed=0, camera_size=size or (320, 240), camera_hz=5.0, cmd_vel_timeout=0)
    try:
        sim.start()
        # a mission listens to odometry and joint states in every case
        subs = [
            rt.bus.subscribe("/odom", Odometry, lambda m: None),
            rt.bus.subscribe("/joint_states", JointState, lambda m: None),
        ]
        if size is not None:
            frames = []
            subs.append(rt.bus.subscribe("/camera/color/image_raw", Image, frames.append))
            subs.append(rt.bus.subscribe("/camera/depth/image_raw", Image, lambda m: None))
        tw = TwistStamped()
        tw.twist.linear.x, tw.twist.angular.z = 0.15, 0.1
        rt.bus.publisher(CMD_VEL, TwistStamped).publish(tw)
        sim.set_arm_positions([0.5, 0.2, 0.3, 0.5], 4.0)
        t0 = time.perf_counter()
        rt.call("sleep", SIM_SECONDS)
        wall = time.perf_counter() - t0
        ms = 1000 * sim.render_seconds / sim.frames_rendered if sim.frames_rendered else float("nan")
        for s in subs:
            s.close()
        return SIM_SECONDS / wall, ms, sim.renderer_name, sim.frames_rendered
    finally:
        sim.close()
        rt.close()


def main() -> int:
    print(
        f"house, {SIM_SECONDS:.0f} s simulated per run, median of {REPEATS} runs; physics 240 Hz "
        f"in 60 Hz control ticks; /odom and /joint_states subscribed (30 Hz)"
    )
    print(f"{'case':26s} {'real-time factor':>17s} {'ms/frame':>9s} {'frames':>7s}  renderer   target")
    bad = []
    for name, size in CASES:
        runs = [run_case(size) for _ in range(REPEATS)]
        rtf = statistics.median(r[0] for r in runs)
        ms = statistics.median(r[1] for r in runs)
        renderer = runs[0][2] if size else "-"
        frames = runs[0][3]
        target = TARGETS.get(name)
        verdict = "" if target is None else (f">= {target:g}x ok" if rtf >= target else f">= {target:g}x MISSED")
        if target is not None and rtf < target:
            bad.append(name)
        ms_txt = f"{ms:9.1f}" if size else f"{'-':>9s}"
        print(f"{name:26s} {rtf:16.1f}x {ms_txt} {frames:7d}  {renderer:9s}  {verdict}", flush=True)
    if bad:
        print("missed targets: " + ", ".join(bad))
    return 0


if __name__ == "__main__":
    sys.exit(main())
