"""Cost of a camera frame (issue [speed]): the sim's own GL renderer (sim/gl_renderer.py,
moderngl on headless EGL) against pybullet's EGL plugin and its TinyRenderer.

For each renderer and world, the robot stands at its start and at a few search locations
(turned each time; in a world without them, near its objects and facing them); at each
pose the camera renders ``--frames`` frames. Reported: the
median ms of the renderer alone (``Renderer.render``: the image and the depth buffer) and
of the whole camera frame the topics publish (``SimWorld.render_camera``: plus the depth
in metres, the world's lighting and depth noise), and the 90th percentile of the latter.

``--png DIR`` (default out/render_compare) saves, per world and pose, the frames of the
three renderers side by side: colour above, depth below (0 m black .. 5 m white).

    .venv/bin/python bench/bench_render.py [--frames 50] [--size 320x240] [--worlds house,house_hard]
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import statistics
import sys
import time

import numpy as np

from sim import SimWorld
from common.quiet_pybullet import pybullet as p
from sim.textures import png_bytes

RENDERERS = ("gl", "egl", "tiny")


def _free(sim, x, y, r=0.25):
    """No wall or furniture within ``r`` of (x, y) in the world's grid."""
    return all(sim.grid.value_at(x + dx, y + dy) == 0 for dx in (-r, 0, r) for dy in (-r, 0, r))


def poses(sim, n):
    """The start, then the search locations (each turned a different way) or, in a world
    without any, 0.8 m from its objects, facing them."""
    out = [None]
    for i, loc in enumerate(sim.spec.search_locations[: n - 1]):
        out.append((loc[0], loc[1], 0.7 + 2.1 * i))
    for name in sim.object_names():
        if len(out) >= n:
            break
        x, y = sim.object_pose(name)[:2]
        for k in range(12):
            a = 2 * math.pi * k / 12
            bx, by = x + 0.8 * math.cos(a), y + 0.8 * math.sin(a)
            if _free(sim, bx, by):
                out.append((bx, by, a + math.pi))
                break
    return out


def place(sim, pose):
    if pose is None:
        return
    x, y, yaw = pose
    _, _, z = p.getBasePositionAndOrientation(sim.robot.body, physicsClientId=sim.cid)[0]
    p.resetBasePositionAndOrientation(
        sim.robot.body, [x, y, z], [0, 0, math.sin(yaw / 2), math.cos(yaw / 2)], physicsClientId=sim.cid
    )


def run(world, renderer, size, frames, n_poses, keep):
    os.environ["ACTORBT_SIM_RENDERER"] = renderer
    sim = SimWorld(None, world, seed=0, camera_size=size)
    try:
        got = sim.renderer_name
        raw, full = [], []
        cam = sim.camera
        for k, pose in enumerate(poses(sim, n_poses)):
            place(sim, pose)
            pos, orn = sim.robot.link_pose("camera_optical_frame")
            look = sim.spec.lighting
            args = (
                cam.width,
                cam.height,
                cam.view(pos, orn),
                cam.projection(),
                None if look is None else look.direction,
            )
            sim.render_camera()  # a warm-up frame (a new size, new bodies)
            for _ in range(frames):
                t0 = time.perf_counter()
                sim._gl_call(sim.renderer.render, *args)  # on the world's GL thread
                raw.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                rgb, depth = sim.render_camera()
                full.append(time.perf_counter() - t0)
            keep.setdefault((world, k), {})[renderer] = (got, rgb, depth)
        return got, raw, full
    finally:
        sim.close()
        os.environ.pop("ACTORBT_SIM_RENDERER", None)


def save_pngs(keep, folder):
    folder.mkdir(parents=True, exist_ok=True)
    for (world, k), by in keep.items():
        tops, bottoms = [], []
        for r in RENDERERS:
            if r not in by:
                continue
            _, rgb, depth = by[r]
            tops.append(rgb)
            d = np.clip(np.nan_to_num(depth, nan=0.0) / 5.0, 0, 1)
            bottoms.append((np.stack([d] * 3, -1) * 255).astype(np.uint8))
        img = np.concatenate([np.concatenate(tops, 1), np.concatenate(bottoms, 1)], 0)
        (folder / f"{world}_pose{k}_{'_'.join(r for r in RENDERERS if r in by)}.png").write_bytes(png_bytes(img))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=50, help="frames per pose and renderer")
    ap.add_argument("--poses", type=int, default=4, help="the start and n-1 search locations")
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--worlds", default="house,house_hard")
    ap.add_argument("--renderers", default=",".join(RENDERERS))
    ap.add_argument("--png", default="out/render_compare", help="folder for side-by-side frames ('' for none)")
    a = ap.parse_args(argv)
    size = tuple(int(x) for x in a.size.split("x"))
    keep: dict = {}
    print(f"camera {size[0]}x{size[1]}, {a.frames} frames at each of {a.poses} poses; ms per frame")
    print(f"{'world':12s} {'renderer':9s} {'got':5s} {'render median':>14s} {'frame median':>13s} {'frame p90':>10s}")
    for world in a.worlds.split(","):
        for r in a.renderers.split(","):
            got, raw, full = run(world, r, size, a.frames, a.poses, keep)
            q = np.percentile(full, 90)
            print(
                f"{world:12s} {r:9s} {got:5s} {1000 * statistics.median(raw):14.2f} "
                f"{1000 * statistics.median(full):13.2f} {1000 * q:10.2f}",
                flush=True,
            )
    if a.png:
        save_pngs(keep, pathlib.Path(a.png))
        print(f"frames side by side ({', '.join(a.renderers.split(','))}; colour above, depth below): {a.png}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
