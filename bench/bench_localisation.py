"""The localiser (navstack.amcl) in the house, synthetic or simulated (issue [senses]).

Each trial: the robot drives a tour of the house with wrong odometry and a noisy LDS-01
laser among unmapped objects; the localiser starts from a rough initial pose. After
``--track`` s the robot is kidnapped (teleported >= 2 m and >= 90 degrees without telling
the localiser) and drives on for ``--after`` s. Reported:

* accuracy, from the 10 Hz pose (odometry between filter updates), after 1 m of travel
  and before the kidnapping: RMS and worst position error, heading RMS;
* the filter update time (median, 95th percentile, max) and the relocalisation time;
* per kidnapping: the time to notice (<= 5 s) and the time until the error is below
  10 cm for good (<= 30 s); last, ``kidnapped recoveries: K/N``.

    .venv/bin/python bench/bench_localisation.py [--trials 20] [--seed 0] [--track 60] [--after 40]
                                                 [--world synthetic|sim] [--set NAME=VALUE] [-v]

The world is a provider (``make_world(seed) -> object`` with ``map``, ``t``, ``odom``,
``truth``, ``distance``, ``step() -> Sample``, ``teleport(pose, target)`` and
``kidnap_pose()``): :class:`navstack.synthetic.SyntheticWorld` (default) or
:class:`SimHouse`, the pybullet simulator (``--world sim``).
"""

from __future__ import annotations

import argparse
import math
import pathlib
import statistics
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from navstack.amcl import Amcl, AmclParams  # noqa: E402
from navstack.map_io import read_map_yaml  # noqa: E402
from navstack.particle_filter import FilterParams  # noqa: E402
from navstack.likelihood_field import LaserModelParams  # noqa: E402
from navstack.synthetic import LaserSpec, SyntheticWorld, world_boxes  # noqa: E402

FIXTURES = ROOT / "tests" / "fixtures"


def synthetic_house(unmapped: int = 8):
    occ = read_map_yaml(FIXTURES / "house.yaml")
    boxes = world_boxes(FIXTURES / "house_world.yaml")
    return lambda seed: SyntheticWorld(occ, boxes, seed=seed, unmapped=unmapped)


class SimHouse:
    """The world provider on the pybullet simulator (``--world sim``): sim.SimWorld's
    house with its objects, its LDS-01 scans and TurtleBot3 odometry, stepped by hand
    (no runtime); the same tour driver as the synthetic world. A kidnapping resets the
    base's pose (the odometry's gyro sees the turn, as a lifted robot's would)."""

    kidnap_pose = SyntheticWorld.kidnap_pose
    _control = SyntheticWorld._control

    def __init__(self, seed: int):
        from navstack.map_io import OccupancyMap
        from navstack.synthetic import HOUSE_TOUR
        from sim import SimWorld

        self.sim = SimWorld(None, "house", seed=seed, camera=False)
        g = self.sim.grid
        self.map = OccupancyMap(g.data, g.resolution, (g.origin[0], g.origin[1], 0.0))
        self.rng = np.random.default_rng(seed)
        self.tour, self.target = list(HOUSE_TOUR), 1  # the house's start is the tour's first point
        self.speed, self.turn = 0.22, 1.2
        self.t, self.dt, self.distance, self._k = 0.0, 0.05, 0.0, 0
        self.truth, self.odom = self.sim.robot_pose(), self.sim.odom_pose()

    def teleport(self, pose, target=None) -> None:
        from common.quiet_pybullet import pybullet as p

        r = self.sim.robot
        pos, _ = p.getBasePositionAndOrientation(r.body, physicsClientId=r.cid)
        p.resetBasePositionAndOrientation(
            r.body, [pose[0], pose[1], pos[2]], p.getQuaternionFromEuler([0, 0, pose[2]]), physicsClientId=r.cid
        )
        self.truth, self.target = tuple(pose), target

    def step(self):
        from navstack.amcl import Scan
        from navstack.synthetic import Sample

        self.sim.apply_cmd_vel(*self._control())
        before = self.truth
        self.sim.advance(self.dt)
        self.t += self.dt
        self._k += 1
        self.truth, self.odom = self.sim.robot_pose(), self.sim.odom_pose()
        self.distance += math.hypot(self.truth[0] - before[0], self.truth[1] - before[1])
        scan = None
        if self._k % 4 == 0:  # 5 Hz
            m = self.sim.lidar_model
            scan = Scan(self.sim.scan(), m.angle_min, m.angle_increment, m.range_min, m.range_max)
        return Sample(self.t, self.odom, self.truth, scan)


def make_localiser(world, seed: int, **overrides) -> Amcl:
    ap, fp, lp = AmclParams(laser_pose=LaserSpec().pose), FilterParams(), LaserModelParams()
    for k, v in overrides.items():
        for obj in (ap, fp, lp):
            if hasattr(obj, k):
                setattr(obj, k, v)
                break
        else:
            raise SystemExit(f"unknown parameter {k}")
    return Amcl(world.map, ap, fp, lp, seed=seed, clock=lambda: world.t)


def err(est, truth):
    return math.hypot(est[0] - truth[0], est[1] - truth[1]), abs(
        (est[2] - truth[2] + math.pi) % (2 * math.pi) - math.pi
    )


def run_trial(make_world, seed: int, track: float, after: float, overrides: dict, verbose=False, trace=False) -> dict:
    world = make_world(seed)
    amcl = make_localiser(world, seed, **overrides)
    rng = np.random.default_rng(seed + 1000)
    x, y, th = world.truth
    init = (x + rng.normal(0, 0.1), y + rng.normal(0, 0.1), th + rng.normal(0, math.radians(5)))
    amcl.on_odometry(world.odom)
    amcl.initialise(init, np.diag([0.2**2, 0.2**2, math.radians(10) ** 2]), odom=world.odom)
    track_err, yaw_err = [], []
    t_kidnap, detected, recovered_at = None, None, None
    next_pose = 0.0
    while True:
        s = world.step()
        amcl.on_odometry(s.odom)
        if s.scan is not None:
            amcl.on_scan(s.scan, s.odom)
            if trace and t_kidnap is not None:
                st, p = amcl.status, amcl.pose(s.odom)
                print(
                    f"    t+{s.t - t_kidnap:5.1f} truth {s.truth[0]:5.2f} {s.truth[1]:5.2f} {s.truth[2]:5.2f}"
                    f"  est {p[0]:5.2f} {p[1]:5.2f} {p[2]:5.2f}  {st.state:9s} score {st.score:.2f}"
                    f" std {st.std_xy:.2f} clusters {st.clusters} n {st.particles} recoveries {st.recoveries}"
                )
        if s.t + 1e-9 < next_pose:
            continue
        next_pose += 0.1  # the pose at 10 Hz
        e, ey = err(amcl.pose(s.odom), s.truth)
        if t_kidnap is None:
            if world.distance >= 1.0:
                track_err.append(e)
                yaw_err.append(ey)
            if s.t >= track:
                false_alarms = amcl.status.lost_count
                pose, target = world.kidnap_pose()
                world.teleport(pose, target)
                t_kidnap = s.t
                lost_before = amcl.status.last_lost
        else:
            if detected is None and amcl.status.last_lost is not None and amcl.status.last_lost != lost_before:
                detected = amcl.status.last_lost - t_kidnap
            if e < 0.10:
                if recovered_at is None:
                    recovered_at = s.t - t_kidnap
            else:
                recovered_at = None
            if s.t >= t_kidnap + after:
                break
    times = amcl.update_times
    if verbose:
        print(
            f"  seed {seed}: rms {1000 * rms(track_err):.0f} mm, worst {1000 * max(track_err):.0f} mm,"
            f" yaw rms {math.degrees(rms(yaw_err)):.2f} deg, noticed after {fmt(detected)} s,"
            f" back under 10 cm after {fmt(recovered_at)} s,"
            f" final err {e:.2f} m, recoveries {amcl.status.recoveries} (false {false_alarms})",
            flush=True,
        )
    return dict(
        track_err=track_err,
        yaw_err=yaw_err,
        update_times=times,
        detected=detected,
        recovered=recovered_at,
        recoveries=amcl.status.recoveries,
        final=e,
        false_alarms=false_alarms,
        search_times=amcl.search_times,
    )


def fmt(v):
    return "-" if v is None else f"{v:.1f}"


def rms(v):
    return math.sqrt(sum(x * x for x in v) / len(v)) if v else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--track", type=float, default=60.0, help="seconds of tracking before the kidnapping")
    ap.add_argument("--after", type=float, default=40.0, help="seconds after the kidnapping")
    ap.add_argument(
        "--world",
        choices=("synthetic", "sim"),
        default="synthetic",
        help="synthetic: the numpy house (fast); sim: the pybullet simulator (about 14 s a trial)",
    )
    ap.add_argument("--unmapped", type=int, default=8, help="unmapped boxes per synthetic world")
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a localiser parameter (AmclParams, FilterParams, LaserModelParams)",
    )
    ap.add_argument("-v", "--verbose", action="store_true")
    ap.add_argument("--trace", type=int, metavar="TRIAL", help="print every scan after the kidnapping in this trial")
    a = ap.parse_args(argv)
    overrides = {}
    for kv in a.set:
        k, v = kv.split("=", 1)
        overrides[k] = eval(v, {"math": math})  # noqa: S307 (a bench knob)
    make_world = synthetic_house(a.unmapped) if a.world == "synthetic" else SimHouse
    wall0 = time.perf_counter()
    results = [
        run_trial(make_world, a.seed + i, a.track, a.after, overrides, a.verbose, a.trace == i) for i in range(a.trials)
    ]
    wall = time.perf_counter() - wall0
    track = [e for r in results for e in r["track_err"]]
    worst_per_trial = [max(r["track_err"]) for r in results]
    yaw = [e for r in results for e in r["yaw_err"]]
    upd = [1000 * t for r in results for t in r["update_times"]]
    ok = [
        r
        for r in results
        if r["detected"] is not None and r["detected"] <= 5.0 and r["recovered"] is not None and r["recovered"] <= 30.0
    ]
    det = [r["detected"] for r in results if r["detected"] is not None]
    rec = [r["recovered"] for r in results if r["recovered"] is not None]
    print(f"{a.world} house, {a.trials} trials, {len(track)} poses at 10 Hz after 1 m of travel ({wall:.0f} s wall)")
    print(
        f"position error: RMS {1000 * rms(track):.1f} mm, worst {1000 * max(track):.1f} mm"
        f" (per-trial worst: median {1000 * statistics.median(worst_per_trial):.0f} mm)"
        f"   (targets <= 50 / <= 100 mm)"
    )
    print(
        f"heading error: RMS {math.degrees(rms(yaw)):.2f} deg, worst {math.degrees(max(yaw)):.2f} deg"
        f"   (target <= 2 deg RMS)"
    )
    print(
        f"filter update: median {statistics.median(upd):.1f} ms, p95 {np.percentile(upd, 95):.1f} ms,"
        f" max {max(upd):.1f} ms over {len(upd)} updates   (target <= 20 ms median)"
    )
    srch = [1000 * t for r in results for t in r["search_times"]]
    if srch:
        print(
            f"global search (relocalisation): median {statistics.median(srch):.0f} ms,"
            f" max {max(srch):.0f} ms over {len(srch)}"
        )
    print(
        f"lost declared while tracking (false alarms): {sum(r['false_alarms'] for r in results)}"
        f" in {a.trials * a.track:.0f} s"
    )
    if det:
        print(
            f"kidnapping noticed: {len(det)}/{a.trials}, after median {statistics.median(det):.1f} s,"
            f" max {max(det):.1f} s   (target <= 5 s)"
        )
    if rec:
        print(
            f"back under 10 cm for good: {len(rec)}/{a.trials}, after median {statistics.median(rec):.1f} s,"
            f" max {max(rec):.1f} s   (target <= 30 s)"
        )
    print(f"kidnapped recoveries: {len(ok)}/{a.trials}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
