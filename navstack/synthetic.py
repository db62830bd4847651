"""A synthetic 2-D world for testing and benchmarking the localiser (not used by it).

It stands for the robot: a differential-drive base following a loop of waypoints, with
wheel odometry that is wrong (a scale error on distance and on turning, a heading drift
and white noise) and an LDS-01-like laser (360 beams, 0.12 .. 3.5 m, noise of 1 cm or
3 % of the range, whichever is larger, a few drop-outs, +inf beyond range) ray-cast
analytically against boxes: the world description's walls and furniture that stand
higher than the scan plane, plus small unmapped boxes (objects on the floor).

A *world provider* is anything with ``map`` (an OccupancyMap), ``step() -> Sample``,
``truth`` and ``teleport(pose)``; :class:`SyntheticWorld` is one; a simulator-backed
provider can replace it in the benchmark.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from .amcl import Scan
from .map_io import OccupancyMap
from .odometry import Pose, as_pose


@dataclass
class Sample:
    t: float  # [s]
    odom: tuple  # odometry pose (x, y, yaw), odom frame
    truth: tuple  # true pose (x, y, yaw), map frame
    scan: Scan | None = None  # a scan taken at this instant, if any


@dataclass
class Boxes:
    """Oriented boxes as arrays: centres (B, 2), half sizes (B, 2), yaws (B,)."""

    centre: np.ndarray
    half: np.ndarray
    yaw: np.ndarray

    @classmethod
    def from_list(cls, boxes) -> Boxes:
        a = np.asarray(boxes, float).reshape(-1, 5)  # cx, cy, sx, sy, yaw
        return cls(a[:, :2].copy(), a[:, 2:4] / 2, a[:, 4].copy())

    def __add__(self, other: Boxes) -> Boxes:
        return Boxes(
            np.vstack([self.centre, other.centre]),
            np.vstack([self.half, other.half]),
            np.concatenate([self.yaw, other.yaw]),
        )

    def __len__(self) -> int:
        return len(self.yaw)

    def contains(self, x: np.ndarray, y: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """(P,) true where a point is inside any box grown by margin."""
        dx = np.asarray(x)[:, None] - self.centre[None, :, 0]
        dy = np.asarray(y)[:, None] - self.centre[None, :, 1]
        c, s = np.cos(self.yaw)[None], np.sin(self.yaw)[None]
        u, v = c * dx + s * dy, -s * dx + c * dy
        return ((np.abs(u) <= self.half[None, :, 0] + margin) & (np.abs(v) <= self.half[None, :, 1] + margin)).any(
            axis=1
        )


def world_boxes(world_yaml: str | Path, scan_height: float = 0.132) -> Boxes:
    """Walls (extended by half a thickness at each end), furniture and the place location
    of a world description (sim/worlds/*.yaml format), those taller than the scan plane."""
    spec = yaml.safe_load(Path(world_yaml).read_text())
    wall = spec.get("wall", {})
    wh, wt = float(wall.get("height", 0.5)), float(wall.get("thickness", 0.1))
    out = []
    if wh > scan_height:
        for x0, y0, x1, y1 in spec.get("walls", []):
            out.append(
                ((x0 + x1) / 2, (y0 + y1) / 2, math.hypot(x1 - x0, y1 - y0) + wt, wt, math.atan2(y1 - y0, x1 - x0))
            )
    items = list(spec.get("furniture", []))
    if "place_location" in spec:
        items.append(spec["place_location"])
    for f in items:
        sx, sy, sz = f["size"]
        if sz > scan_height:
            out.append((f["center"][0], f["center"][1], sx, sy, f.get("yaw", 0.0)))
    return Boxes.from_list(out)


def cast(boxes: Boxes, origin, angles: np.ndarray, max_range: float) -> np.ndarray:
    """Exact distances from ``origin`` (x, y) along ``angles`` to the nearest box
    (slab method in each box's frame); inf when nothing is within max_range."""
    ox, oy = origin
    dx = np.cos(angles)[:, None]
    dy = np.sin(angles)[:, None]
    c, s = np.cos(boxes.yaw)[None], np.sin(boxes.yaw)[None]
    px, py = ox - boxes.centre[None, :, 0], oy - boxes.centre[None, :, 1]
    pu, pv = c * px + s * py, -s * px + c * py  # origin in box frame
    du, dv = c * dx + s * dy, -s * dx + c * dy  # direction in box frame
    hu, hv = boxes.half[None, :, 0], boxes.half[None, :, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        iu, iv = 1.0 / du, 1.0 / dv
        t1u, t2u = (-hu - pu) * iu, (hu - pu) * iu
        t1v, t2v = (-hv - pv) * iv, (hv - pv) * iv
    tmin = np.maximum(np.minimum(t1u, t2u), np.minimum(t1v, t2v))
    tmax = np.minimum(np.maximum(t1u, t2u), np.maximum(t1v, t2v))
    tmin = np.nan_to_num(tmin, nan=-np.inf)
    tmax = np.nan_to_num(tmax, nan=-np.inf)
    hit = (tmax >= np.maximum(tmin, 0.0)) & (tmin > 0)  # origin inside a box: no hit
    t = np.where(hit, tmin, np.inf).min(axis=1)
    t[t > max_range] = np.inf
    return t


@dataclass
class LaserSpec:
    beams: int = 360
    range_min: float = 0.12
    range_max: float = 3.5
    sigma_min: float = 0.01  # [m]
    sigma_rel: float = 0.03  # of the range
    dropout: float = 0.02  # share of beams without a return
    pose: tuple = (-0.15, 0.0, 0.0)  # in the base frame (the robot's LDS sits at the back)


@dataclass
class OdomSpec:
    scale: float = 0.02  # distance scale error (its sign is drawn per world)
    turn_scale: float = 0.02  # turning scale error
    drift: float = math.radians(0.5)  # heading drift [rad/s] while moving (sign drawn)
    sigma_v: float = 0.005  # white noise on speed [m/s]
    sigma_w: float = 0.01  # white noise on turn rate [rad/s]


# a loop through the four rooms of sim/worlds/house.yaml, clear of its furniture
HOUSE_TOUR = [
    (1.0, 1.0),
    (2.2, 1.6),
    (4.8, 1.6),
    (6.0, 2.0),
    (7.2, 2.2),
    (8.6, 2.8),
    (8.0, 3.8),
    (8.0, 5.2),
    (7.5, 5.6),
    (5.6, 5.4),
    (4.8, 6.5),
    (3.3, 6.5),
    (2.8, 5.3),
    (2.0, 5.0),
    (2.0, 3.8),
    (1.0, 3.0),
]


class SyntheticWorld:
    """The robot drives the waypoint loop; ``step()`` advances by ``dt`` and returns the
    odometry, the truth and (every ``scan_period``) a scan."""

    def __init__(
        self,
        occ_map: OccupancyMap,
        boxes: Boxes,
        tour=HOUSE_TOUR,
        *,
        seed: int = 0,
        start: int | None = None,
        reverse: bool | None = None,
        unmapped: int = 8,
        laser: LaserSpec | None = None,
        odom: OdomSpec | None = None,
        dt: float = 0.05,
        scan_period: float = 0.2,
        speed: float = 0.22,
        turn: float = 1.2,
    ):
        self.map = occ_map
        self.rng = rng = np.random.default_rng(seed)
        self.laser = laser or LaserSpec()
        self.odom_spec = o = odom or OdomSpec()
        self.dt, self.scan_period, self.speed, self.turn = dt, scan_period, speed, turn
        tour = [tuple(p) for p in tour]
        if reverse if reverse is not None else rng.random() < 0.5:
            tour = tour[::-1]
        i0 = int(start if start is not None else rng.integers(len(tour)))
        self.tour = tour[i0:] + tour[:i0]
        self.target = 1
        x0, y0 = self.tour[0]
        x1, y1 = self.tour[1]
        self.truth: Pose = (x0, y0, math.atan2(y1 - y0, x1 - x0))
        self.odom = (0.0, 0.0, 0.0)
        self.t = 0.0
        self._next_scan = 0.0
        sign = lambda: 1.0 if rng.random() < 0.5 else -1.0  # noqa: E731
        self._k_v = 1 + sign() * o.scale
        self._k_w = 1 + sign() * o.turn_scale
        self._drift = sign() * o.drift
        self.unmapped = self._unmapped_boxes(boxes, unmapped)
        self.boxes = boxes + self.unmapped if len(self.unmapped) else boxes
        self.angles = np.arange(self.laser.beams) * (2 * math.pi / self.laser.beams)
        self.distance = 0.0  # travelled [m]

    def _unmapped_boxes(self, mapped: Boxes, n: int) -> Boxes:
        """n small boxes on free floor, 0.35 m clear of the tour and 0.1 m of the furniture."""
        free_x, free_y = self.map.cell_centres(self.map.free())
        tour = np.asarray(self.tour + [self.tour[0]])
        out: list[tuple[float, float, float, float, float]] = []  # cx, cy, sx, sy, yaw
        for _ in range(200 * max(n, 1)):
            if len(out) >= n:
                break
            i = self.rng.integers(len(free_x))
            x, y = free_x[i], free_y[i]
            sx, sy = self.rng.uniform(0.05, 0.3, size=2)
            r = math.hypot(sx, sy) / 2
            if _dist_to_polyline(x, y, tour) < 0.35 + r:
                continue
            if mapped.contains(np.array([x]), np.array([y]), r + 0.1)[0]:
                continue
            out.append((x, y, sx, sy, self.rng.uniform(0, math.pi)))
        return Boxes.from_list(out) if out else Boxes(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))

    # -- the world provider interface --------------------------------------------------------
    def teleport(self, pose, target: int | None = None) -> None:
        """Move the robot without telling the odometry (the kidnapped robot), and drive on
        towards tour point ``target`` (the nearest one when None)."""
        self.truth = as_pose(pose)
        if target is None:
            pts = np.asarray(self.tour)
            target = int(np.argmin(np.hypot(pts[:, 0] - pose[0], pts[:, 1] - pose[1])))
        self.target = target

    def kidnap_pose(self, min_dist: float = 2.0, min_turn: float = math.pi / 2):
        """A random pose on the tour, heading along it, at least ``min_dist`` from the
        robot and turned at least ``min_turn`` from its heading; and the tour index to
        drive on to."""
        x, y, th = self.truth
        n = len(self.tour)
        for _ in range(10000):
            i = int(self.rng.integers(n))
            (ax, ay), (bx, by) = self.tour[i], self.tour[(i + 1) % n]
            f = self.rng.uniform(0.1, 0.7)
            px, py = ax + f * (bx - ax), ay + f * (by - ay)
            yaw = math.atan2(by - ay, bx - ax)
            if (
                math.hypot(px - x, py - y) >= min_dist
                and abs((yaw - th + math.pi) % (2 * math.pi) - math.pi) >= min_turn
            ):
                return (px, py, yaw), (i + 1) % n
        raise RuntimeError("no kidnap pose satisfies the distance and turn")

    def step(self) -> Sample:
        v, w = self._control()
        x, y, th = self.truth
        dt = self.dt
        # the truth: exact unicycle integration
        if abs(w) > 1e-9:
            x += v / w * (math.sin(th + w * dt) - math.sin(th))
            y -= v / w * (math.cos(th + w * dt) - math.cos(th))
        else:
            x += v * dt * math.cos(th)
            y += v * dt * math.sin(th)
        self.truth = (x, y, (th + w * dt + math.pi) % (2 * math.pi) - math.pi)
        self.distance += abs(v) * dt
        # the odometry: what the wheels think
        o = self.odom_spec
        moving = abs(v) > 1e-6 or abs(w) > 1e-6
        vo = v * self._k_v + (self.rng.normal(0, o.sigma_v) if moving else 0.0)
        wo = w * self._k_w + ((self._drift + self.rng.normal(0, o.sigma_w)) if moving else 0.0)
        ox, oy, oth = self.odom
        mid = oth + wo * dt / 2
        self.odom = (
            ox + vo * dt * math.cos(mid),
            oy + vo * dt * math.sin(mid),
            (oth + wo * dt + math.pi) % (2 * math.pi) - math.pi,
        )
        self.t += dt
        scan = None
        if self.t + 1e-9 >= self._next_scan:
            self._next_scan += self.scan_period
            scan = self.scan()
        return Sample(self.t, self.odom, self.truth, scan)

    def scan(self) -> Scan:
        L = self.laser
        x, y, th = self.truth
        lx, ly, lyaw = L.pose
        c, s = math.cos(th), math.sin(th)
        origin = (x + c * lx - s * ly, y + s * lx + c * ly)
        r = cast(self.boxes, origin, self.angles + th + lyaw, L.range_max + 0.5)
        finite = np.isfinite(r)
        sigma = np.maximum(L.sigma_min, L.sigma_rel * np.where(finite, r, 0))
        r = np.where(finite, r + self.rng.normal(0, 1, len(r)) * sigma, np.inf)
        r[self.rng.random(len(r)) < L.dropout] = np.inf
        r[(r >= L.range_max)] = np.inf
        r[r < L.range_min] = np.inf
        return Scan(r.astype(np.float32), 0.0, 2 * math.pi / L.beams, L.range_min, L.range_max)

    # -- the driver -------------------------------------------------------------------------
    def _control(self):
        x, y, th = self.truth
        while True:
            gx, gy = self.tour[self.target % len(self.tour)]
            if math.hypot(gx - x, gy - y) > 0.12:
                break
            self.target += 1
        err = (math.atan2(gy - y, gx - x) - th + math.pi) % (2 * math.pi) - math.pi
        if abs(err) > 0.35:
            return 0.0, max(-self.turn, min(self.turn, 2.5 * err))
        return self.speed, max(-self.turn, min(self.turn, 2.0 * err))


def _dist_to_polyline(x: float, y: float, pts: np.ndarray) -> float:
    a, b = pts[:-1], pts[1:]
    ab = b - a
    t = np.clip(((x - a[:, 0]) * ab[:, 0] + (y - a[:, 1]) * ab[:, 1]) / np.maximum((ab**2).sum(1), 1e-12), 0, 1)
    px, py = a[:, 0] + t * ab[:, 0], a[:, 1] + t * ab[:, 1]
    return float(np.min(np.hypot(px - x, py - y)))
