"""Pictures: a top view of a world (map, furniture, place location, objects, robot) and
camera frames."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .objects import CATEGORIES
from .robot import WHEEL_SEPARATION

# chassis footprint in base_footprint (see sim/models/build_urdf.py)
_FOOT = ((-0.205, -0.153), (0.076, -0.153), (0.076, 0.153), (-0.205, 0.153))


def _mpl():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib import patches

    return plt, patches


def _rot(pts, x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return [(x + c * u - s * v, y + s * u + c * v) for u, v in pts]


def _matrix(q):
    """Rotation matrix of a quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _hull(pts):
    """Convex hull (counter-clockwise) of 2-D points."""
    pts = sorted(set(map(tuple, np.round(pts, 5))))
    if len(pts) < 3:
        return pts

    def half(seq):
        out: list[tuple[float, ...]] = []  # the chain so far: (x, y) points
        for pt in seq:
            while (
                len(out) >= 2
                and (
                    (out[-1][0] - out[-2][0]) * (pt[1] - out[-2][1]) - (out[-1][1] - out[-2][1]) * (pt[0] - out[-2][0])
                )
                <= 0
            ):
                out.pop()
            out.append(pt)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return lower[:-1] + upper[:-1]


def draw_top_view(sim, out_png, title=None, dpi=110, overlay=None):
    """Draw a SimWorld's current state from above into ``out_png``; ``overlay(ax)``, when
    given, draws more on the axes (map frame, metres) before saving."""
    plt, patches = _mpl()
    spec, grid = sim.spec, sim.grid
    x0, y0, x1, y1 = spec.bounds
    w_in = 9.0
    fig, ax = plt.subplots(figsize=(w_in, w_in * (y1 - y0) / (x1 - x0) + 0.6))
    img = np.full(grid.data.shape + (3,), 0.62)
    img[grid.data == 0] = (0.97, 0.96, 0.93)
    img[grid.data == 100] = (0.15, 0.15, 0.15)
    ax.imshow(
        img,
        origin="lower",
        extent=(
            grid.origin[0],
            grid.origin[0] + grid.width * grid.resolution,
            grid.origin[1],
            grid.origin[1] + grid.height * grid.resolution,
        ),
        interpolation="nearest",
        zorder=0,
    )
    for name, (rx0, ry0, rx1, ry1) in spec.rooms.items():
        ax.text(
            rx0 + 0.15, ry0 + 0.12, name, ha="left", va="bottom", fontsize=9, color="0.45", style="italic", zorder=1
        )
    for f in spec.furniture:
        ax.add_patch(patches.Polygon(f.corners(), closed=True, fc=f.rgba[:3], ec="0.2", lw=0.8, zorder=2))
        ax.text(f.x, f.y, f.name.replace("_", " "), ha="center", va="center", fontsize=6.5, zorder=3)
    if spec.place is not None:
        pl = spec.place
        ax.add_patch(
            patches.Polygon(pl.corners(), closed=True, fc=(1.0, 0.6, 0.1), ec="k", lw=1.2, hatch="//", zorder=2)
        )
        ax.annotate(
            f"{pl.name} (place)",
            (pl.x, pl.y - pl.sy / 2),
            xytext=(0, -4),
            textcoords="offset points",
            ha="center",
            va="top",
            fontsize=8,
            weight="bold",
            zorder=5,
        )
    colours = {o.name: o.rgba for o in spec.objects if o.rgba is not None}
    for name, pose in sim.object_poses().items():
        cat = CATEGORIES[sim.object_category(name)]
        rgba = colours.get(name, cat.rgba)
        x, y = pose[0], pose[1]
        R = _matrix(pose[3:])
        if R[2, 2] < 0.985:  # lying or leaning (more than 10 deg): its outline from above
            from .varied import part_points

            pts = part_points(cat, 24) @ R.T + np.asarray(pose[:3])
            ax.add_patch(patches.Polygon(_hull(pts[:, :2]), closed=True, fc=rgba[:3], ec="k", lw=0.6, zorder=4))
        elif cat.parts[0][0] == "box":
            yaw = math.atan2(2 * (pose[6] * pose[5] + pose[3] * pose[4]), 1 - 2 * (pose[4] ** 2 + pose[5] ** 2))
            sx, sy = cat.parts[0][1][:2]
            pts = _rot(((-sx / 2, -sy / 2), (sx / 2, -sy / 2), (sx / 2, sy / 2), (-sx / 2, sy / 2)), x, y, yaw)
            ax.add_patch(patches.Polygon(pts, closed=True, fc=rgba[:3], ec="k", lw=0.6, zorder=4))
        else:
            ax.add_patch(patches.Circle((x, y), cat.radius, fc=rgba[:3], ec="k", lw=0.6, zorder=4))
        ax.annotate(name, (x, y), xytext=(6, 6), textcoords="offset points", fontsize=7.5, zorder=5)
    # robot
    rx, ry, ryaw = sim.robot_pose()
    ax.add_patch(
        patches.Polygon(
            _rot(_FOOT, rx, ry, ryaw), closed=True, fc=(0.3, 0.55, 0.85), ec="k", lw=1.0, alpha=0.9, zorder=6
        )
    )
    for s in (1, -1):
        ax.add_patch(
            patches.Polygon(
                _rot(
                    (
                        (-0.033, s * WHEEL_SEPARATION / 2 - 0.009),
                        (0.033, s * WHEEL_SEPARATION / 2 - 0.009),
                        (0.033, s * WHEEL_SEPARATION / 2 + 0.009),
                        (-0.033, s * WHEEL_SEPARATION / 2 + 0.009),
                    ),
                    rx,
                    ry,
                    ryaw,
                ),
                closed=True,
                fc="k",
                zorder=7,
            )
        )
    # camera field of view
    cam = sim.camera
    half = math.radians(cam.hfov_deg) / 2
    rng = 1.2
    cx, cy = _rot([(0.09, 0.0)], rx, ry, ryaw)[0]
    fov = [(cx, cy)] + [
        (cx + rng * math.cos(ryaw + a), cy + rng * math.sin(ryaw + a)) for a in np.linspace(-half, half, 12)
    ]
    ax.add_patch(patches.Polygon(fov, closed=True, fc=(0.3, 0.55, 0.85), alpha=0.15, ec="none", zorder=5))
    ax.annotate(
        "", xy=_rot([(0.35, 0)], rx, ry, ryaw)[0], xytext=(rx, ry), arrowprops=dict(arrowstyle="->", lw=1.5), zorder=8
    )
    ee = sim.link_pose("end_effector_link")[0]
    ax.plot([ee[0]], [ee[1]], marker="+", color="k", ms=7, zorder=8)
    if overlay is not None:
        overlay(ax)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"{spec.name} (seed {spec.seed}): robot, objects, place location", fontsize=10)
    ax.grid(True, lw=0.3, alpha=0.4)
    fig.tight_layout()
    out_png = Path(out_png)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=dpi)
    plt.close(fig)
    return out_png


def write_camera_png(sim, out_png):
    """One camera frame: RGB on the left, depth (near = bright, NaN = black) on the right."""
    import cv2

    rgb, depth = sim.render_camera()
    d = np.nan_to_num(depth, nan=np.inf)
    vis = np.where(np.isfinite(d), 1.0 - np.clip(d / 4.0, 0, 1), 0.0)
    dimg = cv2.applyColorMap((vis * 255).astype(np.uint8), cv2.COLORMAP_VIRIDIS)
    dimg[~np.isfinite(d)] = 0
    out = np.hstack([rgb[:, :, ::-1], dimg])
    cv2.putText(out, f"rgb ({sim.renderer_name})", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
    cv2.putText(out, "depth 0-4 m", (rgb.shape[1] + 6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
    out_png = Path(out_png)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out_png), out)
    return out_png


def snapshot(world="house", seed=0, out_png="world.png", camera=False, camera_size=(640, 480)):
    """Build the world (no runtime), let it settle, write the top view (and camera frame)."""
    from .simworld import SimWorld

    sim = SimWorld(None, world, seed, camera=camera, camera_size=camera_size)
    try:
        sim.advance(0.5)
        out = [draw_top_view(sim, out_png)]
        if camera:
            p = Path(out_png)
            out.append(write_camera_png(sim, p.with_name(p.stem + "_camera.png")))
        return out
    finally:
        sim.close()
