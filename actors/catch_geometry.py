"""The geometry of the catch actors (actors/catch.py), as pure functions: the discs that
cover the base's outline, where a target is and where the hand closes on it, the marks
that keep the way to a lying target off it, the order of standoff views after a failed
grasp, and the spots on a surface to put objects down on; with the constants they and
the actors share.
"""

from __future__ import annotations

import math
from typing import Any

from bt_engine import ActorbtError

from .ros_conv import wrap
from .strategies import GraspPlan

STANDOFF_CLEARANCE = 0.26  # room the base needs around a standoff pose [m]
#: the base's outline in base_footprint, x_min, x_max, |y| max [m]: the Waffle Pi chassis.
#: Along the straight drive in, only this must stay clear of the map's obstacles: the
#: arm and the hand are above a table whose edge the base stops at.
BASE_OUTLINE = (-0.205, 0.076, 0.153)
BASE_MARGIN = 0.025  # room kept between that outline and an obstacle [m]
OUTLINE_REACH = math.hypot(-BASE_OUTLINE[0], BASE_OUTLINE[2])  # its farthest corner [m]
SAME_OBJECT = 0.12  # detections closer than this to the target are the target [m]
PLACE_SPACING = 0.11  # [m] between the axes of objects put down on one surface
PLACE_EDGE_MARGIN = 0.06  # [m] an object's axis stays this far from a surface's corner
NEW_VIEW = math.radians(25)  # after a failed grasp, headings this close to it come last
MARK_SPACING = 0.03  # [m] between the discs that mark a lying target on the way to it
MARK_MARGIN = 0.02  # [m] around the target's body, marked on the way to it
FINGERTIPS = 0.024  # [m] the finger pads end this far ahead of the tool point


def segment_distance(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """Distance from point ``p`` to the segment ``a``-``b`` [m]."""
    (px, py), (ax, ay), (bx, by) = p, a, b
    dx, dy = bx - ax, by - ay
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / ((dx * dx + dy * dy) or 1e-12)))
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


def outline_discs(
    pose: tuple[float, float, float], outline: tuple[float, float, float] = BASE_OUTLINE, spacing: float = 0.07
) -> tuple[list[tuple[float, float]], float]:
    """Discs that together cover the base's rectangular ``outline`` at ``pose`` (x, y,
    heading): their centres in the map frame and their common radius [m]. The base is
    clear of obstacles when each centre is farther than that radius from all of them."""
    x_min, x_max, half_y = outline
    nx = max(1, math.ceil((x_max - x_min) / spacing))
    ny = max(1, math.ceil(2 * half_y / spacing))
    cell_x, cell_y = (x_max - x_min) / nx, 2 * half_y / ny
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    centres = []
    for i in range(nx):
        for j in range(ny):
            bx, by = x_min + (i + 0.5) * cell_x, -half_y + (j + 0.5) * cell_y
            centres.append((x + c * bx - s * by, y + s * bx + c * by))
    return centres, 0.5 * math.hypot(cell_x, cell_y)


def target_xy(target: Any) -> tuple[float, float]:
    try:
        return float(target["x"]), float(target["y"])
    except (TypeError, KeyError, ValueError):
        raise ActorbtError(f"a target needs numeric 'x' and 'y' (map frame), got {target!r}") from None


def grasp_xy(target: dict, plan: GraspPlan) -> tuple[float, float]:
    """Where the hand closes, seen from above: the target's x, y; for a leaning object, the
    point of its axis at the grasp's height (perception's ``axis_base`` and ``axis_dir``)."""
    base, up = target.get("axis_base"), target.get("axis_dir")
    if target.get("pose") != "tilted" or not base or not up or up[2] < 0.3:
        return target_xy(target)
    t = plan.height / up[2]
    return base[0] + t * up[0], base[1] + t * up[1]


def ends_swapped(a: dict, b: dict) -> bool:
    """Do two sightings of a lying body take its base and top for each other?"""
    ua, ub = a.get("axis_dir"), b.get("axis_dir")
    if a.get("pose") != "lying" or b.get("pose") != "lying" or not ua or not ub:
        return False
    return ua[0] * ub[0] + ua[1] * ub[1] + ua[2] * ub[2] < 0


def object_yaw(target: dict, plan: GraspPlan) -> float | None:
    """The direction the plan's ``sides`` are relative to: the target's ``yaw``; for a plan
    that comes from one side only, the direction from the object's base to its top (a
    lying body's ``yaw`` is its axis's, either way)."""
    up = target.get("axis_dir")
    if plan.one_way and up and math.hypot(up[0], up[1]) > 0.3:
        return math.atan2(up[1], up[0])
    return target.get("yaw")


def target_marks(target: dict, length: float, goal: tuple[float, float]) -> list[dict]:
    """The target itself as obstacles (x, y, radius) for the drive to ``goal`` (a look
    or standoff pose's x, y): too low for the lidar, a lying body is otherwise driven over
    and pushed. A lying body (``length`` [m] long) is marked along its axis; discs
    within STANDOFF_CLEARANCE of the goal are left out, so the goal keeps its room."""
    x, y = target_xy(target)
    r = max(0.03, float(target.get("width") or 0.07) / 2) + MARK_MARGIN
    pts = [(x, y)]
    if target.get("pose") == "lying" and length > 0:
        base, up = target.get("axis_base"), target.get("axis_dir")
        if base and up and math.hypot(up[0], up[1]) > 0.3:
            n = math.hypot(up[0], up[1])
            (ux, uy), (bx, by) = (up[0] / n, up[1] / n), (base[0], base[1])
        elif target.get("yaw") is not None:
            ux, uy = math.cos(target["yaw"]), math.sin(target["yaw"])
            bx, by = x - 0.5 * length * ux, y - 0.5 * length * uy
        else:
            ux = uy = 0.0
            bx, by, r = x, y, 0.5 * length + MARK_MARGIN
        k = max(1, math.ceil(length / MARK_SPACING))
        pts += [(bx + i / k * length * ux, by + i / k * length * uy) for i in range(k + 1)]
    return [{"x": px, "y": py, "radius": r} for px, py in pts if math.dist((px, py), goal) - r >= STANDOFF_CLEARANCE]


def fresh_views_first(
    poses: list[tuple[float, float, float]], xy: tuple[float, float], failed_views: list[tuple[float, float, float]]
) -> list[tuple[float, float, float]]:
    """Standoff ``poses`` (x, y, heading) with those within NEW_VIEW of the heading of a
    failed grasp of the object at ``xy`` (``failed_views``: x, y, heading) moved last, so
    that a retry comes from a new view."""
    failed = [h for fx, fy, h in failed_views if math.dist((fx, fy), xy) <= SAME_OBJECT]
    stale = [any(abs(wrap(p[2] - h)) < NEW_VIEW for h in failed) for p in poses]
    return [p for p, st in zip(poses, stale) if not st] + [p for p, st in zip(poses, stale) if st]


def seen_again(target: dict, seen: dict) -> dict:
    """``target`` updated with a new detection of it, ``seen``. Its base's height is the
    lower of the two: perception puts it at the lowest part in view, and from near, the
    camera (looking down) sees only the top of an object on a table, and the next pick
    would aim the hand as high above the table as the object is tall."""
    out = {**target, **seen}
    if isinstance(target.get("z"), (int, float)) and isinstance(seen.get("z"), (int, float)):
        out["z"] = min(float(target["z"]), float(seen["z"]))
    return out


def surface_spots(
    surface: tuple[float, float, float, float],
    inset: float,
    standoff: float,
    taken: list,
    robot: tuple[float, float],
    yaw: float = 0.0,
) -> list[tuple[float, ...]]:
    """Where an object may be put down on a box-shaped surface (x, y, size_x, size_y) [m]
    turned ``yaw`` [rad] (its sizes along its own axes): ``inset`` inside an edge, along it
    PLACE_SPACING apart (the middle first), at least PLACE_SPACING from the ``taken``
    spots. Each (x, y, heading of the base facing the surface across that edge, and the
    standoff x, y ``standoff`` back from it), nearest the ``robot`` (x, y) first."""
    x, y, size_x, size_y = surface
    c, s = math.cos(yaw), math.sin(yaw)
    spots = []
    for nx, ny, half, along in (
        (1.0, 0.0, size_x / 2, size_y / 2),
        (-1.0, 0.0, size_x / 2, size_y / 2),
        (0.0, 1.0, size_y / 2, size_x / 2),
        (0.0, -1.0, size_y / 2, size_x / 2),
    ):
        nx, ny = c * nx - s * ny, s * nx + c * ny  # the edge's outward normal, map frame
        heading = math.atan2(-ny, -nx)
        for k in (0, 1, -1, 2, -2):
            t = k * PLACE_SPACING
            if abs(t) > along - PLACE_EDGE_MARGIN:
                continue
            px, py = x + nx * (half - inset) - ny * t, y + ny * (half - inset) + nx * t
            if any(math.dist((px, py), q) < PLACE_SPACING for q in taken):
                continue
            sx, sy = px - standoff * math.cos(heading), py - standoff * math.sin(heading)
            # a spot off the edge's middle costs a little: the middle is the surest
            spots.append((math.dist((sx, sy), robot) + 0.05 * abs(k), px, py, heading, sx, sy))
    return [spot[1:] for spot in sorted(spots)]
