"""Perception in house_hard: is each category object recognised, in its pose, from nearby?

For every seed, every category object of the world (upright, lying or tilted; on the floor
or a low table; labelled, under varied light, with depth noise) is looked at from
``--views`` viewpoints 0.45-0.9 m away (``--band``; 1.1-1.8 m for one on a low table) that
the robot's base could occupy (lidar-height clearance from the world's grid), facing it.
Each view renders one camera frame and runs ``detect()`` with the camera's true pose (this
measures perception, not localisation).

Reported per category and pose: views where the object is in the image; recognised (a
detection of its category within 6 cm of its body centre); the pose reported right;
position error of the body centre (x, y) and of the base's height (z, against the object's
lowest point) median / 95th percentile; and, over all views,
false detections (a category reported where no object of it is).

Distractors (objects of no registered category) are looked at the same way: seen as an
object of no known category at their place (what lets the robot's close look reject a
distractor taken for a category from afar), seen as a category (false), or not seen. And
over all views: objects of no known category reported where no object is (parts of
furniture taken for objects).

    .venv/bin/python bench/bench_perception_hard.py [--seeds 10] [--views 4] [--band 0.45,0.9] [--png DIR]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
from collections import defaultdict

import numpy as np

from actors.camera import Intrinsics, RGBDFrame
from actors.perception import detect, registered_appearances
from sim import SimWorld
from common.quiet_pybullet import pybullet as p

MATCH = 0.06  # [m] a detection this close to the body centre is the object
FALSE = 0.12  # [m] a category detection farther than this from any of its objects
DECOY_MATCH = 0.08  # [m] a detection this close to a distractor's origin is of it
STRAY = 0.15  # [m] an unknown object farther than this from every object is none


def _pose_matrix(pos, orn) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
    T[:3, 3] = pos
    return T


def _frame(sim: SimWorld) -> RGBDFrame:
    rgb, depth = sim.render_camera()
    cam = sim.camera
    k = cam.K()
    intr = Intrinsics(k[0], k[4], k[2], k[5], cam.width, cam.height, "camera_optical_frame")
    return RGBDFrame(
        0.0,
        np.ascontiguousarray(rgb[:, :, ::-1]),
        depth,
        intr,
        _pose_matrix(*sim.link_pose("camera_optical_frame")),
        _pose_matrix(*sim.link_pose("base_footprint")),
        "map",
    )


def _free(sim: SimWorld, x: float, y: float, clearance: float = 0.2) -> bool:
    g = sim.grid
    row, col = g.cell(x, y)
    r = int(math.ceil(clearance / g.resolution))
    if not (r <= row < g.height - r and r <= col < g.width - r):
        return False
    return not (g.data[row - r : row + r + 1, col - r : col + r + 1] != 0).any()


def _teleport(sim: SimWorld, x: float, y: float, yaw: float) -> None:
    body = sim.robot.body
    pos, _ = p.getBasePositionAndOrientation(body, physicsClientId=sim.cid)
    p.resetBasePositionAndOrientation(
        body, [x, y, pos[2]], p.getQuaternionFromEuler([0, 0, yaw]), physicsClientId=sim.cid
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", default="house_hard")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--views", type=int, default=4)
    ap.add_argument(
        "--band",
        default="0.45,0.9",
        help="near,far [m]: the distances of the views of an object on the floor (0.33,0.45: from the grasp standoffs)",
    )
    ap.add_argument("--png", default=None, help="save each missed view's frame here")
    ap.add_argument("--verbose", action="store_true")
    args = ap.parse_args()
    band = tuple(float(v) for v in args.band.split(","))

    apps = registered_appearances()
    rows = defaultdict(lambda: {"views": 0, "seen": 0, "pose": 0, "err": [], "z_err": []})
    decoys = defaultdict(lambda: {"views": 0, "unknown": 0, "category": 0})
    false = views_total = stray = 0
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        sim = SimWorld(None, args.world, seed=seed)
        rng = np.random.default_rng(seed)
        decoy_rng = np.random.default_rng(seed + 100_000)  # the category views stay as they were
        try:
            placed_by_name = {o.name: o for o in sim.spec.objects}
            truth = {n: (sim.object_category(n), placed_by_name[n]) for n in sim.object_names()}
            poses = sim.object_poses()
            for name, (cat, placed) in truth.items():
                pose = poses[name]
                if cat not in apps:
                    ox, oy, oz = pose[:3]
                    _look_at_decoy(sim, decoy_rng, args.views, apps, (ox, oy, oz), band, decoys[cat])
                    continue
                # the point perception reports: the middle of the body (a bottle's, not its neck)
                R = np.array(p.getMatrixFromQuaternion(pose[3:])).reshape(3, 3)
                app = apps[cat]
                ox, oy, oz = np.array(pose[:3]) + R @ [0.0, 0.0, 0.5 * app.body_top - 0.5 * app.height]
                for got, frame in _views(sim, rng, args.views, (ox, oy, oz), band):
                    dets = detect(frame, apps)
                    views_total += 1
                    key = (cat, placed.pose_kind)
                    row = rows[key]
                    row["views"] += 1
                    hit = [
                        dd for dd in dets if dd["category"] == cat and math.dist((dd["x"], dd["y"]), (ox, oy)) < MATCH
                    ]
                    if hit:
                        row["seen"] += 1
                        row["err"].append(1000 * math.dist((hit[0]["x"], hit[0]["y"]), (ox, oy)))
                        # the base: the support's height, the lowest point of the object
                        lowest = p.getAABB(sim.scene.objects[name], physicsClientId=sim.cid)[0][2]
                        row["z_err"].append(1000 * abs(hit[0]["z"] - lowest))
                        if (hit[0].get("pose") or "upright") == placed.pose_kind:
                            row["pose"] += 1
                    elif args.png:
                        import cv2

                        cv2.imwrite(f"{args.png}/miss_s{seed}_{name}_{got}.png", frame.bgr)
                    if args.verbose and not hit:
                        print(
                            f"  seed {seed} {name} {placed.pose_kind} on {placed.support} view {got}: "
                            f"missed; saw {[(dd['category'], round(dd['x'], 2), round(dd['y'], 2)) for dd in dets]}"
                            f" (object at {ox:.2f}, {oy:.2f})"
                        )
                    stray += sum(
                        1
                        for dd in dets
                        if dd["category"] not in apps
                        and min(math.dist((dd["x"], dd["y"]), q[:2]) for q in poses.values()) > STRAY
                    )
                    for dd in dets:
                        if dd["category"] in apps and not any(
                            c == dd["category"] and math.dist((dd["x"], dd["y"]), poses[n][:2]) < FALSE
                            for n, (c, _) in truth.items()
                        ):
                            false += 1
                            if args.verbose:
                                print(
                                    f"  seed {seed} view of {name}: false {dd['category']} at "
                                    f"({dd['x']:.2f}, {dd['y']:.2f})"
                                )
        finally:
            sim.close()
        print(f"seed {seed} done", file=sys.stderr)

    print(
        f"{'category':10s} {'pose':8s} {'views':>5s} {'recognised':>10s} {'pose ok':>8s} "
        f"{'err med':>8s} {'err p95':>8s} {'z err med':>9s} {'z err p95':>9s}  [mm]"
    )
    for (cat, kind), row in sorted(rows.items()):
        err, z_err = row["err"], row["z_err"]
        print(
            f"{cat:10s} {kind:8s} {row['views']:5d} {row['seen'] / row['views']:10.0%} "
            f"{row['pose'] / max(1, row['seen']):8.0%} "
            f"{statistics.median(err) if err else float('nan'):8.1f} "
            f"{float(np.percentile(err, 95)) if err else float('nan'):8.1f} "
            f"{statistics.median(z_err) if z_err else float('nan'):9.1f} "
            f"{float(np.percentile(z_err, 95)) if z_err else float('nan'):9.1f}"
        )
    print(f"false category detections: {false} in {views_total} views")
    print(f"objects of no known category where no object is: {stray} in {views_total} views")
    print(f"\n{'distractor':10s} {'views':>5s} {'unknown':>8s} {'category':>8s} {'unseen':>7s}")
    total = {"views": 0, "unknown": 0, "category": 0}
    for kind, row in sorted(decoys.items()) + [("all", total)]:
        if kind != "all":
            for k in total:
                total[k] += row[k]
        v = max(1, row["views"])
        print(
            f"{kind:10s} {row['views']:5d} {row['unknown'] / v:8.0%} {row['category'] / v:8.0%} "
            f"{(row['views'] - row['unknown'] - row['category']) / v:7.0%}"
        )
    return 0


def _views(sim: SimWorld, rng, views: int, at: tuple, band: tuple[float, float]):
    """(1, 2, ...; the camera frame) of ``views`` views of the object at ``at`` (x, y, z),
    from free places at random directions, ``band`` [m] away (1.1-1.8 m for one on a low
    table: the camera, 9 cm up, sees over its edge only from farther), facing it."""
    ox, oy, oz = at
    near, far = band if oz < 0.15 else (1.1, 1.8)
    got = 0
    for _ in range(200):
        if got >= views:
            break
        a, d = rng.uniform(-math.pi, math.pi), rng.uniform(near, far)
        # the camera sits ahead of base_footprint: stand so that it sees the object
        x, y = ox - d * math.cos(a), oy - d * math.sin(a)
        if not _free(sim, x, y):
            continue
        got += 1
        _teleport(sim, x, y, a)
        yield got, _frame(sim)


def _look_at_decoy(sim: SimWorld, rng, views: int, apps: dict, at: tuple, band: tuple[float, float], row: dict) -> None:
    """Views of a distractor at ``at`` (its x, y, z), as of a category object: seen as of no
    known category there, as a category, or not at all."""
    for _, frame in _views(sim, rng, views, at, band):
        at_it = [dd for dd in detect(frame, apps) if math.dist((dd["x"], dd["y"]), at[:2]) < DECOY_MATCH]
        row["views"] += 1
        if any(dd["category"] in apps for dd in at_it):
            row["category"] += 1
        elif at_it:
            row["unknown"] += 1


if __name__ == "__main__":
    sys.exit(main())
