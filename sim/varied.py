"""Placement for worlds whose objects take varied poses (``poses:`` in a world
description, e.g. house_hard): each object stands upright, lies on its side or leans
against a wall or a piece of furniture, on the floor or (upright) near the edge of a low
table (furniture with ``support: true``); plus distractors (``distractors:``).

Every choice comes from the world seed, in streams of their own:
``[seed, 21]`` pose kinds, supports and tilts; ``seed`` positions (as in every world);
``[seed, 23]`` distractors; ``[seed, 29]`` colours. Same seed, same world.

Reachability (the simulator does not import the planner; tests check these against
``planning.ArmKinematics``): an object on a table stands ``r + 15..50 mm`` inside an edge
whose floor in front is free for the base at the category's grasp reach and approach
standoff; a leaning object has that free floor on its room side; a lying one along one
end of its axis. The base (base_footprint to its front bumper: ``CHASSIS_FRONT``) never
needs to drive under or onto a table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import categories as registry

from .objects import CATEGORIES, DECOYS
from .textures import jitter_rgba
from .world_spec import Distractors, PlacedObject, PoseMix

CHASSIS_FRONT = 0.076  # base_footprint to the front of the chassis [m]
CHASSIS_REAR = 0.205
CHASSIS_HALF_WIDTH = 0.153
DEFAULT_REACH, DEFAULT_STANDOFF = 0.27, 0.12
MAX_TILT_DEG = 55.0  # beyond this a "tilted" object is laid down instead
LEAN_GAP = 0.002  # between a leaning object and its support at placement [m]


# ----------------------------------------------------------------------------- geometry
def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def quat_of(R) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix."""
    m = np.asarray(R, float)
    t = m[0, 0] + m[1, 1] + m[2, 2]
    if t > 0:
        s = 2 * math.sqrt(t + 1)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    else:
        i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2 * math.sqrt(1 + m[i, i] - m[j, j] - m[k, k])
        q = [0.0, 0.0, 0.0, (m[k, j] - m[j, k]) / s]
        q[i] = s / 4
        q[j] = (m[j, i] + m[i, j]) / s
        q[k] = (m[k, i] + m[i, k]) / s
    v = np.array(q)
    v /= np.linalg.norm(v)
    if v[3] < 0:
        v = -v
    x, y, z, w = (float(c) for c in v)
    return x, y, z, w


def part_points(model, n: int = 48) -> np.ndarray:
    """Points on the outline of a model's parts, in its frame: both rims of each cylinder,
    every corner of each box."""
    pts = []
    for part in model.parts:
        if part[0] == "cylinder":
            _, r, length, zc = part
            a = np.linspace(0, 2 * math.pi, n, endpoint=False)
            for z in (zc - length / 2, zc + length / 2):
                pts += list(zip(r * np.cos(a), r * np.sin(a), np.full(n, z)))
        elif part[0] == "box":
            (sx, sy, sz), zc = part[1], part[2]
            pts += [(u * sx / 2, v * sy / 2, zc + w * sz / 2) for u in (-1, 1) for v in (-1, 1) for w in (-1, 1)]
        else:  # sphere
            _, r, zc = part
            pts += [(r * u, r * v, zc + r * w) for u, v, w in np.eye(3).tolist() + (-np.eye(3)).tolist()]
    return np.array(pts, float)


def centre_of_mass(model) -> np.ndarray:
    vols, zs = [], []
    for part in model.parts:
        if part[0] == "cylinder":
            vols.append(math.pi * part[1] ** 2 * part[2])
            zs.append(part[3])
        elif part[0] == "box":
            vols.append(float(np.prod(part[1])))
            zs.append(part[2])
        else:
            vols.append(4 / 3 * math.pi * part[1] ** 3)
            zs.append(part[2])
    return np.array([0.0, 0.0, float(np.dot(vols, zs) / sum(vols))])


def is_round(model) -> bool:
    return all(part[0] == "cylinder" for part in model.parts)


def lying_rotations(model) -> list[np.ndarray]:
    """The ways the model lies on its side: a body of revolution on its curved side;
    anything else also on the faces its x and y axes point through."""
    if is_round(model):
        return [rot_x(math.pi / 2)]
    return [rot_x(math.pi / 2), rot_y(math.pi / 2)]


@dataclass(frozen=True)
class Lean:
    """A model tilted by ``theta`` towards +x (its own yaw ``phi`` first), in a frame whose
    support face is the plane x = 0 and whose floor is z = 0."""

    theta: float
    phi: float
    R: np.ndarray  # object -> lean frame rotation
    x: float  # frame position (x < 0: in front of the face)
    z: float
    contact_z: float  # height of its highest point against the face
    reach: float  # largest horizontal distance of its outline from its frame


def lean(model, theta: float, phi: float) -> Lean | None:
    """The model leaning at ``theta`` [rad] against a face at x = 0; None when it would not
    stay (its centre of mass not beyond the edge it pivots on, towards the face)."""
    R = rot_y(theta) @ rot_z(phi)
    pts = part_points(model) @ R.T
    com = R @ centre_of_mass(model)
    zmin = pts[:, 2].min()
    pivot = pts[pts[:, 2] <= zmin + 1e-4]
    if com[0] - pivot[:, 0].max() < 0.004:
        return None
    i = int(np.argmax(pts[:, 0]))
    x = -(LEAN_GAP + pts[i, 0])
    return Lean(theta, phi, R, x, -zmin + 1e-3, pts[i, 2] - zmin, float(np.hypot(pts[:, 0], pts[:, 1]).max()))


def stable_lean(model, theta_deg: float, phi: float) -> Lean | None:
    """``lean`` at ``theta_deg``; if it would not stay, 3 deg steeper than the least angle
    that does, up to MAX_TILT_DEG; None beyond."""
    t0 = max(1.0, float(theta_deg))
    for t in np.arange(t0, MAX_TILT_DEG + 1e-9, 0.5):
        if lean(model, math.radians(t), phi) is not None:
            t = t if t == t0 else min(t + 3.0, MAX_TILT_DEG)
            return lean(model, math.radians(t), phi)
    return None


# ----------------------------------------------------------------------------- placement
def _facing_yaw(cat_name: str, heading: float, u: float) -> float:
    """The yaw of an object on a table, from ``u`` drawn in [-pi, pi): any for a round
    one; a box's is turned so that a side its grasp takes it from faces the base coming
    along ``heading`` across the free edge, within half the grasp's tolerance (else the
    hand could reach it from a side with no room for the base only: a carton at a
    table's end, its narrow side towards the wall)."""
    try:
        plan = registry.get(cat_name).strategy.plan_for("upright")
    except registry.UnknownCategoryError:
        return u
    if plan is None or not plan.sides:
        return u
    side = plan.sides[int((u + math.pi) / (2 * math.pi) * len(plan.sides)) % len(plan.sides)]
    jitter = 0.5 * plan.tolerance * math.sin(3.0 * u)  # spread, from the same draw
    flip = math.pi if u > 0 and not plan.one_way else 0.0
    return math.remainder(heading - side + flip + jitter, 2 * math.pi)


def _grasp_reach(cat_name: str, kind: str) -> tuple[float, float]:
    """(reach, standoff) of the robot's grasp for a category in a pose kind."""
    try:
        cat = registry.get(cat_name)
    except registry.UnknownCategoryError:
        return DEFAULT_REACH, DEFAULT_STANDOFF
    if kind == "lying":
        return cat.top_grasp.reach, cat.approach.standoff
    return cat.approach.reach, cat.approach.standoff


class Placer:
    """Seeded placement of one world's objects with varied poses."""

    def __init__(self, spec, clearance, tries, mix: PoseMix, seed, robot_radius, door_clearance):
        self.spec, self.clearance, self.tries, self.mix = spec, clearance, tries, mix
        self.R, self.door = robot_radius, door_clearance
        self.rng = np.random.default_rng(seed)  # positions
        self.pose_rng = np.random.default_rng([seed, 21])  # kinds, supports, tilts
        self.statics = spec.obstacles
        self.leanable = [b for b in list(spec.walls) + list(spec.furniture)]
        self.tables = [f for f in spec.furniture if getattr(f, "support", False)]
        self.placed: list[tuple[float, float, float]] = []  # floor footprints (x, y, r)
        self.on_table: dict[str, list] = {t.name: [] for t in self.tables}
        self.keepout: list[tuple[float, float, float]] = []  # robot spots kept free
        self.ends = []
        for w in spec.walls:
            c, s = math.cos(w.yaw), math.sin(w.yaw)
            h = w.sx / 2
            self.ends += [(w.x - c * h, w.y - s * h), (w.x + c * h, w.y + s * h)]

    # -- checks
    def floor_free(self, x, y, r, margin, doorways=True, ignore=None):
        for ob in self.statics:
            if ob is not ignore and ob.distance(x, y) < r + margin:
                return False
        if doorways:
            for ex, ey in self.ends:
                if math.hypot(x - ex, y - ey) < self.door + r:
                    return False
        rx, ry, _ = self.spec.robot_start
        if math.hypot(x - rx, y - ry) < self.R + r + margin:
            return False
        for px, py, pr in self.placed:
            if math.hypot(x - px, y - py) < r + pr + margin:
                return False
        for kx, ky, kr in self.keepout:
            if math.hypot(x - kx, y - ky) < kr + r + 0.05:
                return False
        return True

    def base_fits(self, ox, oy, heading, reach, standoff):
        """The base can stand facing ``heading`` with the object ``reach`` ahead of
        base_footprint, and back off to the standoff, on free floor."""
        c, s = math.cos(heading), math.sin(heading)
        x0, y0, x1, y1 = self.spec.bounds
        margin = 0.03
        # where it backs off to, turning freely: the disc round the chassis clear
        bx, by = ox - (reach + standoff) * c, oy - (reach + standoff) * s
        if any(ob.distance(bx, by) < self.R + 0.02 for ob in self.statics):
            return False
        if any(math.hypot(bx - qx, by - qy) < self.R + qr + 0.02 for qx, qy, qr in self.placed):
            return False
        for k in np.linspace(0.0, standoff, 4):
            bx, by = ox - (reach + k) * c, oy - (reach + k) * s
            # the chassis as a grid of points over its rectangle
            for along in np.linspace(-CHASSIS_REAR, CHASSIS_FRONT, 4):
                for side in (-CHASSIS_HALF_WIDTH, 0.0, CHASSIS_HALF_WIDTH):
                    px, py = bx + along * c - side * s, by + along * s + side * c
                    if not (x0 <= px <= x1 and y0 <= py <= y1):
                        return False
                    if any(ob.distance(px, py) < margin for ob in self.statics):
                        return False
                    if any(math.hypot(px - qx, py - qy) < margin + qr for qx, qy, qr in self.placed):
                        return False
        return True

    def keep(self, ox, oy, heading, reach, standoff):
        d = reach + standoff - 0.065
        self.keepout.append((ox - d * math.cos(heading), oy - d * math.sin(heading), 0.2))

    # -- one object
    def place(self, name, cat, room, kind=None, support=None):
        """A PlacedObject for ``cat`` in ``room`` (None: anywhere), or None when no spot is
        free. ``kind``/``support`` force the pose kind and the support."""

        model = CATEGORIES[cat]
        prng = self.pose_rng
        # a fixed number of draws per object, so one object's choice leaves the next alone
        u_kind, u_table, u_tilt, u_phi, u_lie = prng.random(5)
        if kind is None:
            kind = self.mix.pick(u_kind)
        if support is None:
            tables = self._tables_in(room)
            support = "floor"
            if kind == "upright" and tables and u_table < self.mix.on_tables:
                support = tables[int(u_table / self.mix.on_tables * len(tables)) % len(tables)].name
        if support != "floor":
            got = self._on_table(name, cat, model, support)
            if got is not None:
                return got
            if kind != "upright":
                return None
        if kind == "tilted":
            lo, hi = self.mix.tilt_deg
            got = self._tilted(name, cat, model, room, lo + u_tilt * (hi - lo), u_phi)
            if got is not None:
                return got
            kind = "lying"  # nothing to lean on here: lie down instead
        if kind == "lying":
            rots = lying_rotations(model)
            return self._lying(name, cat, model, room, rots[int(u_lie * len(rots)) % len(rots)])
        r = model.radius
        found = self._floor_spot(room, r, self.clearance)
        if found is None:
            return None
        x, y = found
        yaw = float(self.rng.uniform(-math.pi, math.pi))
        self.placed.append((x, y, r))
        return PlacedObject(name, cat, x, y, yaw)

    def _tables_in(self, room):
        if room is None:
            return list(self.tables)
        x0, y0, x1, y1 = self.spec.rooms[room]
        return [t for t in self.tables if x0 <= t.x <= x1 and y0 <= t.y <= y1]

    def _floor_spot(self, room, r, clearance, extra=None):
        area = self.spec.rooms[room] if room else self.spec.bounds
        ax0, ay0, ax1, ay1 = area
        lo_x, hi_x = ax0 + r + clearance, ax1 - r - clearance
        lo_y, hi_y = ay0 + r + clearance, ay1 - r - clearance
        if lo_x > hi_x or lo_y > hi_y:
            return None
        for _ in range(self.tries):
            x, y = self.rng.uniform(lo_x, hi_x), self.rng.uniform(lo_y, hi_y)
            if self.floor_free(x, y, r, clearance) and (extra is None or extra(x, y)):
                return float(x), float(y)
        return None

    def _on_table(self, name, cat, model, table_name):

        table = next(t for t in self.tables if t.name == table_name)
        r = model.radius
        reach, standoff = _grasp_reach(cat, "upright")
        faces = []  # (outward normal angle, half length along the edge, half depth)
        for k, (hl, hd) in enumerate(((table.sy / 2, table.sx / 2), (table.sx / 2, table.sy / 2)) * 2):
            faces.append((table.yaw + k * math.pi / 2, hl, hd))
        for _ in range(self.tries):
            ang, hl, hd = faces[int(self.rng.integers(4))]
            inset = r + float(self.rng.uniform(0.015, 0.05))
            if hl - r - 0.02 <= 0 or inset + r > 2 * hd or reach - inset - CHASSIS_FRONT < 0.03:
                continue
            t = float(self.rng.uniform(-(hl - r - 0.02), hl - r - 0.02))
            nx, ny = math.cos(ang), math.sin(ang)
            ox = table.x + nx * (hd - inset) - ny * t
            oy = table.y + ny * (hd - inset) + nx * t
            if any(ob is not table and ob.distance(ox, oy) < r + 0.02 for ob in self.statics):
                continue
            if any(math.hypot(ox - qx, oy - qy) < r + qr + 0.06 for qx, qy, qr in self.on_table[table.name]):
                continue
            heading = ang + math.pi  # the base faces the table
            if not self.base_fits(ox, oy, heading, reach, standoff):
                continue
            self.on_table[table.name].append((ox, oy, r))
            self.keep(ox, oy, heading, reach, standoff)
            yaw = _facing_yaw(cat, heading, float(self.rng.uniform(-math.pi, math.pi)))
            return PlacedObject(
                name, cat, ox, oy, yaw, z=table.sz + model.height / 2 + 1e-4, pose_kind="upright", support=table.name
            )
        return None

    def _tilted(self, name, cat, model, room, theta_deg, u_phi):

        phis = [0.0] if is_round(model) else [0.0, math.pi / 2]
        phi = phis[int(u_phi * len(phis)) % len(phis)]
        if is_round(model):
            phi = u_phi * 2 * math.pi  # turned about its own axis: any way
        ln = stable_lean(model, theta_deg, phi)
        if ln is None and not is_round(model):
            ln = stable_lean(model, theta_deg, phis[1 - phis.index(phi)] if len(phis) > 1 else phi)
        if ln is None:
            return None
        reach, standoff = _grasp_reach(cat, "tilted")
        area = self.spec.rooms[room] if room else self.spec.bounds
        faces = []  # (box, face centre x, y, outward normal angle, usable half length)
        for b in self.leanable:
            if b.sz < ln.contact_z + 0.01 or b is self.spec.place:
                continue
            for k in range(4):
                ang = b.yaw + k * math.pi / 2
                hl, hd = (b.sy / 2, b.sx / 2) if k % 2 == 0 else (b.sx / 2, b.sy / 2)
                use = hl - ln.reach - 0.05
                if use <= 0:
                    continue
                fx, fy = b.x + hd * math.cos(ang), b.y + hd * math.sin(ang)
                faces.append((b, fx, fy, ang, use))
        if not faces:
            return None
        weights = np.array([f[4] for f in faces])
        weights /= weights.sum()
        for _ in range(self.tries):
            b, fx, fy, ang, use = faces[int(self.rng.choice(len(faces), p=weights))]
            t = float(self.rng.uniform(-use, use))
            nx, ny = math.cos(ang), math.sin(ang)
            d = -ln.x  # frame distance in front of the face
            ox, oy = fx + nx * d - ny * t, fy + ny * d + nx * t
            if not (area[0] <= ox <= area[2] and area[1] <= oy <= area[3]):
                continue
            if not self.floor_free(ox, oy, ln.reach, 0.05, ignore=b):
                continue
            if any(math.hypot(ox - px, oy - py) < ln.reach + pr + self.clearance for px, py, pr in self.placed):
                continue
            heading = ang + math.pi
            if not self.base_fits(ox, oy, heading, reach, standoff):
                continue
            psi = ang + math.pi  # lean frame +x: towards the face
            R = rot_z(psi) @ ln.R
            self.placed.append((ox, oy, ln.reach))
            self.keep(ox, oy, heading, reach, standoff)
            return PlacedObject(
                name,
                cat,
                ox,
                oy,
                float(math.atan2(math.sin(psi), math.cos(psi))),
                z=ln.z,
                quat=quat_of(R),
                pose_kind="tilted",
                support=b.name,
            )
        return None

    def _lying(self, name, cat, model, room, R0):

        pts = part_points(model) @ R0.T
        z = float(-pts[:, 2].min() + 1e-3)
        r = float(np.hypot(pts[:, 0], pts[:, 1]).max())
        reach, standoff = _grasp_reach(cat, "lying")
        yaw = float(self.rng.uniform(-math.pi, math.pi))
        axis = R0 @ np.array([0.0, 0.0, 1.0])  # the lying body's axis, before yaw
        ax_yaw = yaw + math.atan2(axis[1], axis[0])

        def approachable(x, y):
            return any(self.base_fits(x, y, ax_yaw + k * math.pi, reach, standoff) for k in (0, 1))

        found = self._floor_spot(room, r, self.clearance, extra=approachable)
        if found is None:
            return None
        x, y = found
        self.placed.append((x, y, r))
        return PlacedObject(name, cat, x, y, yaw, z=z, quat=quat_of(rot_z(yaw) @ R0), pose_kind="lying")

    # -- distractors
    def distractors(self, spec_d: Distractors, seed, taken: set):
        """PlacedObjects of distractor models, recoloured near the categories' hues."""

        rng = np.random.default_rng([seed, 23])
        crng = np.random.default_rng([seed, 29, 1])
        kinds = [k for k in spec_d.kinds if k not in registry.names()]
        palette = [tuple(c.rgba) + (1.0,) * (4 - len(c.rgba)) for c in registry.all_categories()]
        out: list[PlacedObject] = []
        counters: dict[str, int] = {}
        n = int(rng.integers(spec_d.count[0], spec_d.count[1] + 1)) if kinds else 0
        rooms = sorted(self.spec.rooms)
        for _ in range(n):
            kind = kinds[int(rng.integers(len(kinds)))]
            room = rooms[int(rng.integers(len(rooms)))] if rooms else None
            u_table = rng.random()
            k = counters.get(kind, 0) + 1
            while f"{kind}_{k}" in taken:
                k += 1
            counters[kind] = k
            name = f"{kind}_{k}"
            model = DECOYS[kind]
            base = palette[int(crng.integers(len(palette)))] if palette else model.rgba
            rgba = jitter_rgba(base, crng, hue=0.04, saturation=0.25, value=0.25)
            got = None
            tables = self._tables_in(room)
            if tables and u_table < spec_d.on_tables:
                table = tables[int(u_table / spec_d.on_tables * len(tables)) % len(tables)]
                got = self._decoy_on_table(name, kind, model, table)
            if got is None:
                found = self._floor_spot(room, model.radius, self.clearance)
                if found is None:
                    continue  # a crowded room: one distractor fewer
                self.placed.append((found[0], found[1], model.radius))
                got = PlacedObject(name, kind, found[0], found[1], float(self.rng.uniform(-math.pi, math.pi)))
            taken.add(name)
            out.append(_with(got, rgba=rgba))
        return out

    def _decoy_on_table(self, name, kind, model, table):

        r = model.radius
        c, s = math.cos(table.yaw), math.sin(table.yaw)
        half_u, half_v = table.sx / 2 - r - 0.02, table.sy / 2 - r - 0.02  # where the decoy's centre may go
        for _ in range(50):
            u = float(self.rng.uniform(-half_u, half_u)) if table.sx > 2 * r + 0.04 else None
            v = float(self.rng.uniform(-half_v, half_v)) if table.sy > 2 * r + 0.04 else None
            if u is None or v is None:
                return None
            ox, oy = table.x + c * u - s * v, table.y + s * u + c * v
            if any(math.hypot(ox - qx, oy - qy) < r + qr + 0.06 for qx, qy, qr in self.on_table[table.name]):
                continue
            self.on_table[table.name].append((ox, oy, r))
            return PlacedObject(
                name,
                kind,
                ox,
                oy,
                float(self.rng.uniform(-math.pi, math.pi)),
                z=table.sz + model.height / 2 + 1e-4,
                support=table.name,
            )
        return None


def _with(obj, **kw):
    from dataclasses import replace

    return replace(obj, **kw)
