"""Record a mapping run of the simulator once, then replay it through navstack's SLAM as
often as you like (issue [maps]): a change to the SLAM is judged in a minute on real
simulator data instead of a ten-minute exploration.

    .venv/bin/python bench/mapping_replay.py record --world house --seed 0 --out out/rec0.npz
    .venv/bin/python bench/mapping_replay.py replay out/rec0.npz [--set pair_edges=2 ...] [--edges]

``record`` runs ``actorbt map build``'s exploration (:func:`demo.mapping.build_map`) and
keeps every ``/scan``, ``/odom`` and IMU message and, as the referee, the simulator's true
pose at each scan. ``replay`` feeds the scans to :class:`navstack.slam.Slam` as the mapper
does (the odometry turned by the IMU's heading, :class:`navstack.gyro_odometry.GyroOdometry`,
interpolated at each scan's stamp; a recording without IMU messages: the wheels' alone),
with ``--set`` overriding SlamParams (values are YAML), and prints:

* ``online``: the pose error as the robot drove (the newest keyframe's pose plus the
  odometry since, what the mapper publishes) [cm, RMS and max];
* ``keyframes``: the error of the optimised keyframe trajectory at the end [cm RMS];
  the scale of a similarity fit to the truth (1: none) and what is left after it, and
  after a rigid fit;
* precision and recall of the saved map against the world at the lidar's height
  (``actorbt map score``);
* with ``--edges``: each pose-graph edge kind's error along its own translation, against
  the truth [mm, and mm per metre of edge]: a negative figure is a shrink.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import tempfile
import time

import numpy as np
import yaml

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


# -- recording -------------------------------------------------------------------------------
def record(world: str, seed: int, out: pathlib.Path, max_time: float) -> None:
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import LaserScan

    from demo.mapping import build_map
    from sensor_msgs.msg import Imu

    from navstack.localiser import IMU_TOPIC
    from navstack.odometry import yaw_of

    rec: dict = {"scan_t": [], "ranges": [], "truth": [], "odom": [], "imu": [], "meta": None}

    def observe(rt, sim):
        def on_scan(m: LaserScan) -> None:
            rec["scan_t"].append(m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec)
            rec["ranges"].append(np.asarray(m.ranges, np.float32))
            rec["truth"].append(tuple(sim.robot_pose()))  # the referee's view, never the robot's
            rec["meta"] = rec["meta"] or [m.angle_min, m.angle_increment, m.range_min, m.range_max]

        def on_odom(m: Odometry) -> None:
            p = m.pose.pose
            rec["odom"].append(
                (m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec, p.position.x, p.position.y, yaw_of(p.orientation))
            )

        def on_imu(m: Imu) -> None:
            rec["imu"].append((m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec, yaw_of(m.orientation)))

        subs = [
            rt.bus.subscribe("/scan", LaserScan, on_scan, 100),
            rt.bus.subscribe("/odom", Odometry, on_odom, 100),
            rt.bus.subscribe(IMU_TOPIC, Imu, on_imu, 100),
        ]
        return lambda: [s.close() for s in subs]

    with tempfile.TemporaryDirectory() as tmp:
        run = build_map(world, seed, tmp, max_time=max_time, observe=observe, progress=sys.stdout)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        out,
        scan_t=np.array(rec["scan_t"]),
        ranges=np.array(rec["ranges"]),
        truth=np.array(rec["truth"]),
        odom=np.array(rec["odom"]),
        imu=np.array(rec["imu"]).reshape(-1, 2),
        meta=np.array(rec["meta"]),
        world=np.array(world),
        seed=np.array(seed),
    )
    print(
        f"recorded {len(rec['scan_t'])} scans, {len(rec['odom'])} odometry and {len(rec['imu'])} IMU messages of a "
        f"{run.sim_time:.0f} s run in {out}; live: online error {100 * run.traj_rmse_m:.1f} cm RMS "
        f"({100 * run.traj_max_m:.1f} max), {run.mapping.get('loop_closures')} loop closures"
    )


# -- replaying -------------------------------------------------------------------------------
def fit(truth: np.ndarray, est: np.ndarray, scale: bool) -> tuple[float, float]:
    """Least-squares est ~ s R truth + t (Umeyama): (s, RMS left [m])."""
    mt, me = truth.mean(0), est.mean(0)
    a, b = truth - mt, est - me
    u, sv, vt = np.linalg.svd(b.T @ a / len(a))
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    rot = u @ d @ vt
    s = float((sv * np.diag(d)).sum() / (a**2).sum() * len(a)) if scale else 1.0
    left = b - s * (rot @ a.T).T
    return s, float(np.sqrt((left**2).sum(1).mean()))


def replay(path: pathlib.Path, overrides: dict, edges: bool = False) -> dict:
    from navstack.map_io import write_map_yaml
    from navstack.gyro_odometry import GyroOdometry
    from navstack.odometry import OdomHistory
    from navstack.pose_graph import relative
    from navstack.log_odds import LogOddsParams
    from navstack.slam import Slam, SlamParams
    from sim.gridmap import read_map
    from sim.map_score import score_maps, truth_grid

    with np.load(path) as npz:  # each access of an npz member reads it again
        d = {k: npz[k] for k in npz.files}
    angle_min, angle_inc, range_min, range_max = (float(v) for v in d["meta"])
    angles = angle_min + angle_inc * np.arange(d["ranges"].shape[1])
    grid = {k.removeprefix("grid."): v for k, v in overrides.items() if k.startswith("grid.")}
    params = {
        "sensor_offset": (-0.15, 0.0, 0.0),  # the URDF's base_scan
        **{k: v for k, v in overrides.items() if not k.startswith("grid.")},
    }
    if grid:
        params["grid"] = LogOddsParams(**{**SlamParams().grid.__dict__, **grid})
    slam = Slam(SlamParams(initial_pose=tuple(d["truth"][0]), **params))
    odom, online = OdomHistory(maxlen=1 << 20), []
    messages = odometry_messages(d["odom"], d.get("imu", np.zeros((0, 2))))
    gyro, next_msg = GyroOdometry(), 0
    t0 = time.perf_counter()
    for k, t in enumerate(d["scan_t"]):
        while next_msg < len(messages) and messages[next_msg][0] <= t + 1e-9:
            stamp, kind, value = messages[next_msg]
            if kind == "imu":
                gyro.on_imu(stamp, value)
            else:
                odom.add(stamp, gyro.fuse(stamp, value))
            next_msg += 1
        o = odom.at(t)
        if o is None:
            continue
        slam.add(o, d["ranges"][k], angles, range_max, t, range_min=range_min, gyro=gyro.gyro_heading)
        est, true = slam.pose(), d["truth"][k]
        online.append(math.hypot(est[0] - true[0], est[1] - true[1]))
    wall = time.perf_counter() - t0
    truth_at = {t: d["truth"][k] for k, t in enumerate(d["scan_t"])}
    kf_true = np.array([truth_at[kf.t] for kf in slam.keyframes])
    kf_est = np.array([slam.graph.pose(i) for i in range(len(slam.keyframes))])
    err = np.hypot(*(kf_est[:, :2] - kf_true[:, :2]).T)
    scale, after_similarity = fit(kf_true[:, :2], kf_est[:, :2], True)
    _, after_rigid = fit(kf_true[:, :2], kf_est[:, :2], False)
    with tempfile.TemporaryDirectory() as tmp:
        yaml_path = pathlib.Path(tmp) / "map.yaml"
        write_map_yaml(slam.map(), yaml_path)
        built = read_map(yaml_path).grid
    world, seed = str(d["world"]), int(d["seed"])
    score = score_maps(built, truth_grid(world, seed, resolution=built.resolution))
    out = {
        "online_rms_cm": 100 * float(np.sqrt(np.mean(np.square(online)))),
        "online_max_cm": 100 * max(online),
        "keyframes_rms_cm": 100 * float(np.sqrt(np.mean(err**2))),
        "scale": scale,
        "after_similarity_cm": 100 * after_similarity,
        "after_rigid_cm": 100 * after_rigid,
        "precision": score.precision,
        "recall": score.recall,
        "keyframes": len(slam.keyframes),
        "loop_closures": slam.loop_closures,
        "slam_wall_s": wall,
    }
    if edges:
        out["edges"] = edge_errors(slam, kf_true, relative)
    return out


def odometry_messages(odom: np.ndarray, imu: np.ndarray) -> list[tuple]:
    """/odom and IMU messages merged by stamp, as the mapper receives them: (t, "odom",
    (x, y, yaw)) and (t, "imu", yaw); an IMU reading before an odometry one at the same stamp."""
    msgs = [(float(r[0]), "imu", float(r[1])) for r in imu] + [(float(r[0]), "odom", tuple(r[1:])) for r in odom]
    return sorted(msgs, key=lambda m: (m[0], m[1] != "imu"))


def edge_errors(slam, kf_true: np.ndarray, relative) -> dict:
    """Per edge kind (pair links by their span): the error along the edge's own
    translation against the truth: mean [mm] and per metre of edge [mm/m]."""
    rows: dict[str, list] = {}
    turns: dict[str, list] = {}
    for e in slam.graph.edges:
        kind = e.kind if e.kind != "pair" else f"pair{e.j - e.i}"
        zt = relative(kf_true[e.i], kf_true[e.j])
        turns.setdefault(kind, []).append((math.remainder(e.z[2] - zt[2], 2 * math.pi), zt[2]))
        n = math.hypot(zt[0], zt[1])
        if n < 0.05:
            continue  # a turn on the spot: no direction
        along = ((e.z[0] - zt[0]) * zt[0] + (e.z[1] - zt[1]) * zt[1]) / n
        rows.setdefault(kind, []).append((along, n))
    out = {}
    for k in sorted(turns):
        v, yaw = rows.get(k, [(0.0, 1.0)]), np.array(turns[k])
        out[k] = {
            "n": len(turns[k]),
            "mean_mm": 1000 * float(np.mean([a for a, _ in v])),
            "per_metre_mm": 1000 * sum(a for a, _ in v) / sum(n for _, n in v),
            "yaw_mdeg": 1000 * math.degrees(float(yaw[:, 0].mean())),
            # the yaw error per radian turned (a rotation "shrink" is negative)
            "yaw_per_turn": float((yaw[:, 0] * yaw[:, 1]).sum() / max((yaw[:, 1] ** 2).sum(), 1e-12)),
        }
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record", help="run a mapping exploration and record /scan, /odom and the truth")
    r.add_argument("--world", default="house")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--max-time", type=float, default=900.0)
    r.add_argument("--out", type=pathlib.Path, required=True)
    p = sub.add_parser("replay", help="replay a recording through the SLAM and score it")
    p.add_argument("recording", type=pathlib.Path)
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a navstack.slam.SlamParams field (the value is YAML); "
        "grid.FIELD: a field of its occupancy grid's LogOddsParams",
    )
    p.add_argument("--edges", action="store_true", help="also the pose-graph edges' errors")
    p.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    shown = argv if argv is not None else sys.argv[1:]
    print("$ " + " ".join([".venv/bin/python", "bench/mapping_replay.py"] + shown))
    if args.cmd == "record":
        record(args.world, args.seed, args.out, args.max_time)
        return 0
    overrides = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            ap.error(f"--set {item!r}: expected KEY=VALUE")
        overrides[key] = yaml.safe_load(value)
    res = replay(args.recording, overrides, args.edges)
    if args.json:
        print(json.dumps(res))
        return 0
    print(
        f"online {res['online_rms_cm']:.1f} cm RMS ({res['online_max_cm']:.1f} max); keyframes "
        f"{res['keyframes_rms_cm']:.1f} cm RMS, scale {res['scale']:.4f}, {res['after_similarity_cm']:.1f} cm "
        f"after a similarity fit, {res['after_rigid_cm']:.1f} cm after a rigid one; precision "
        f"{res['precision']:.3f} recall {res['recall']:.3f}; {res['keyframes']} keyframes, "
        f"{res['loop_closures']} loop closures, SLAM {res['slam_wall_s']:.0f} s wall"
    )
    for kind, e in res.get("edges", {}).items():
        print(
            f"  {kind:6s} {e['n']:4d} edges: along-track error {e['mean_mm']:+6.2f} mm mean, "
            f"{e['per_metre_mm']:+6.2f} mm/m; yaw error {e['yaw_mdeg']:+6.1f} mdeg mean, "
            f"{1000 * e['yaw_per_turn']:+6.2f} mrad per rad turned"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
