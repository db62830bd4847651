"""Cost of the simulated robot's own senses (issue [senses]): the LDS-01 scan (one batch
ray cast of 360 beams) and the wheel odometry, and what a /scan subscriber does to the
simulator's speed.

1. ms per scan in `house` (median over many scans, at several robot poses);
2. microseconds per odometry update (the model alone, and with the two pybullet reads the
   world does every control tick);
3. the simulator's real-time factor on `house` (the robot drives an arc, the arm moves;
   /odom and /joint_states subscribed) without and with a /scan subscriber; also per CPU
   second of this process (simulated s / CPU s), which other load on the machine disturbs less;
4. the reference demo (`make demo`: bt_pick_place, house, seed 0) without and with a
   /scan subscriber (skip it with --no-demo).

    .venv/bin/python bench/bench_sim_sensors.py [--no-demo]
"""

from __future__ import annotations

import io
import math
import statistics
import sys
import time

from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, LaserScan

from bt_engine import Runtime
from sim import SimWorld
from common.quiet_pybullet import pybullet as p
from sim.odometry import OdomNoise, WheelOdometry, episode_rng
from sim.topics import CMD_VEL

SCANS = 300
POSES = [(1.0, 1.0, 0.0), (3.0, 1.5, 1.2), (7.5, 2.5, -2.0), (5.0, 6.0, 0.5), (2.0, 6.0, 3.0)]
SIM_SECONDS = 10.0
REPEATS = 5  # pairs of runs, without and with /scan, interleaved (the machine's load drifts)


def bench_scan():
    sim = SimWorld(None, "house", seed=0, camera=False)
    try:
        times = []
        for x, y, yaw in POSES:
            # teleport the robot: the scan only reads geometry
            p.resetBasePositionAndOrientation(
                sim.robot.body, [x, y, 0.0], [0, 0, math.sin(yaw / 2), math.cos(yaw / 2)], physicsClientId=sim.cid
            )
            pos, orn = sim.robot.link_pose("base_scan")
            for _ in range(SCANS // len(POSES)):
                t0 = time.perf_counter()
                sim.lidar.scan(pos, orn)
                times.append(time.perf_counter() - t0)
        return 1000 * statistics.median(times), 1000 * max(times)
    finally:
        sim.close()


def bench_odom():
    odo = WheelOdometry(OdomNoise(), episode_rng(0))
    odo.reset(0.0, 0.0, 0.0)
    n = 20000
    t0 = time.perf_counter()
    for i in range(1, n + 1):
        odo.update(0.12 * i, 0.13 * i, 1 / 60, 0.001 * i)
    model_us = 1e6 * (time.perf_counter() - t0) / n
    sim = SimWorld(None, "house", seed=0, camera=False)
    try:
        m = 5000
        t0 = time.perf_counter()
        for _ in range(m):
            q = sim.robot.joint_states()[0]
            sim.odometry.update(q[0], q[1], 1 / 60, sim.robot.base_pose()[0][2])
        tick_us = 1e6 * (time.perf_counter() - t0) / m
    finally:
        sim.close()
    return model_us, tick_us


def run_sim(with_scan: bool):
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "house", seed=0, camera=False, cmd_vel_timeout=0)
    try:
        sim.start()
        subs = [
            rt.bus.subscribe("/odom", Odometry, lambda m: None),
            rt.bus.subscribe("/joint_states", JointState, lambda m: None),
        ]
        scans = []
        if with_scan:
            subs.append(rt.bus.subscribe("/scan", LaserScan, scans.append, "sensor"))
        tw = TwistStamped()
        tw.twist.linear.x, tw.twist.angular.z = 0.15, 0.1
        rt.bus.publisher(CMD_VEL, TwistStamped).publish(tw)
        sim.set_arm_positions([0.5, 0.2, 0.3, 0.5], 4.0)
        t0, c0 = time.perf_counter(), time.process_time()
        rt.call("sleep", SIM_SECONDS)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        for s in subs:
            s.close()
        return SIM_SECONDS / wall, len(scans), sim.lidar.seconds / wall, SIM_SECONDS / cpu
    finally:
        sim.close()
        rt.close()


def run_demo(with_scan: bool):
    from demo.episode import run_episode

    scans, worlds = [], []

    def setup(world):
        worlds.append(world)
        if with_scan:
            world.runtime.bus.subscribe("/scan", LaserScan, scans.append, "sensor")

    c0 = time.process_time()
    ep = run_episode("bt_pick_place", "house", 0, "any", progress=io.StringIO(), world_setup=setup)
    return ep, len(scans), worlds[0].lidar.seconds, time.process_time() - c0


def main() -> int:
    demo = "--no-demo" not in sys.argv[1:]
    med, worst = bench_scan()
    print(
        f"scan (360 beams, one rayTestBatch, house): median {med:.2f} ms, max {worst:.2f} ms "
        f"over {SCANS} scans at {len(POSES)} poses"
    )
    model_us, tick_us = bench_odom()
    print(
        f"odometry update: {model_us:.1f} us (model), {tick_us:.1f} us with the per-tick "
        f"pybullet reads (wheel joints + base yaw)"
    )
    print(
        f"\nsimulator on house, {SIM_SECONDS:.0f} s simulated, median of {REPEATS}; "
        f"/odom and /joint_states subscribed, camera off"
    )
    pairs = [(run_sim(False), run_sim(True)) for _ in range(REPEATS)]
    for with_scan in (False, True):
        runs = [pair[with_scan] for pair in pairs]
        rtf = statistics.median(r[0] for r in runs)
        share = statistics.median(r[2] for r in runs)
        per_cpu = statistics.median(r[3] for r in runs)
        label = "with /scan subscribed" if with_scan else "without /scan"
        print(
            f"  {label:24s} {rtf:6.1f}x real time, {per_cpu:5.1f}x per CPU second   ({runs[0][1]} scans, "
            f"{100 * share:.1f} % of the wall time casting)",
            flush=True,
        )
    if demo:
        print("\ndemo (bt_pick_place, house, seed 0; the actors' camera is on)")
        for with_scan in (False, True):
            ep, n, cast, cpu = run_demo(with_scan)
            label = "with /scan subscribed" if with_scan else "without /scan"
            print(
                f"  {label:24s} {ep.realtime_factor:6.1f}x real time, {ep.sim_time / cpu:5.1f}x per CPU "
                f"second   sim {ep.sim_time:.1f} s, wall {ep.wall_time:.1f} s, "
                f"{'success' if ep.success else 'FAILED'}, {n} scans ({cast:.2f} s casting, "
                f"{100 * cast / ep.wall_time:.1f} % of the wall time)",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
