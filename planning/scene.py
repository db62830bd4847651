"""The planning scene: a collision model of the robot and what it knows of the world.

Like MoveIt's planning scene, it is separate from the simulator: its own pybullet
``DIRECT`` client holds the robot (loaded from the same URDF), with the base fixed
at the origin of the model root frame (``base_footprint``), and the obstacles the
caller tells it about: static ones, and ones added or removed at run time such as
a table or a perceived object. An obstacle can also be attached to the gripper,
so that it moves with the arm while it is carried.

Collision rules (the allowed-collision matrix):

* A link pair is never checked when the arm joints cannot change the links'
  relative pose (both on the mobile base, or both in the gripper), when the links
  are parent and child (pybullet's own rule for self-collision), or when the pair
  collides in every one of a few hundred random configurations (MoveIt Setup
  Assistant's "always in collision").
* World obstacles are checked against the links moved by the arm, not against the
  base, which touches the floor by design.
* World obstacles are padded by ``padding`` [m] on every side; self-collision has
  no padding.

Checks are serialised by a lock (OMPL's PRM checks states from two threads);
changing obstacles while a query runs in another thread is not supported.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from common.quiet_pybullet import pybullet

from .errors import InvalidInputError, SceneError
from .kinematics import ArmKinematics, JointValues

__all__ = ["Obstacle", "Contact", "CollisionReport", "PlanningScene"]

_FLOOR = "floor"


@dataclass(frozen=True)
class Obstacle:
    """A collision object of the scene, in the model root frame.

    Attributes:
        name: unique name in the scene.
        shape: ``"box"``, ``"cylinder"`` or ``"sphere"``.
        size: box full extents (x, y, z) [m]; cylinder (radius, height) [m];
            sphere (radius,) [m]. The cylinder axis is the object's z axis.
        position: centre (x, y, z) [m].
        orientation: quaternion (x, y, z, w).
        attached_to: link the object moves with, or None for a world object.
    """

    name: str
    shape: Literal["box", "cylinder", "sphere"]
    size: tuple[float, ...]
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    attached_to: str | None = None


@dataclass(frozen=True)
class Contact:
    """One colliding pair.

    Attributes:
        a, b: link or obstacle names.
        distance: signed distance [m], negative when penetrating (padding included).
    """

    a: str
    b: str
    distance: float


@dataclass(frozen=True)
class CollisionReport:
    """The outcome of checking one configuration.

    Attributes:
        valid: True when the state is inside the limits and collision-free.
        within_limits: False when some joint is outside its limits.
        contacts: colliding pairs, one entry per pair (deepest point).
    """

    valid: bool
    within_limits: bool
    contacts: tuple[Contact, ...]

    def describe(self) -> str:
        """One line for an error message."""
        if self.valid:
            return "valid"
        parts = [] if self.within_limits else ["outside the joint limits"]
        parts += [f"{c.a} touches {c.b} ({c.distance * 1000:.1f} mm)" for c in self.contacts[:4]]
        if len(self.contacts) > 4:
            parts.append(f"and {len(self.contacts) - 4} more pairs")
        return "; ".join(parts)


class PlanningScene:
    """Collision model of the arm, its base and known obstacles.

    Args:
        kinematics: the arm model; built from ``urdf`` when omitted.
        urdf: robot URDF (default: the repository robot).
        padding: margin added around world obstacles [m].
        floor: add a ``"floor"`` obstacle whose top is the plane z = 0 of the
            root frame (remove it with ``remove("floor")``).
        fixed_joints: positions of the other movable joints during checks,
            e.g. the gripper fingers [m] (default: URDF zero / the lower limit).
        acm_samples: random configurations used to find always-colliding pairs.
        seed: seed of that sampling.
    """

    def __init__(
        self,
        kinematics: ArmKinematics | None = None,
        *,
        urdf: str | os.PathLike[str] | None = None,
        padding: float = 0.01,
        floor: bool = True,
        fixed_joints: Mapping[str, float] | None = None,
        acm_samples: int = 300,
        seed: int = 0,
    ) -> None:
        if not (math.isfinite(padding) and padding >= 0):
            raise InvalidInputError(f"padding must be >= 0 m, got {padding!r}")
        self.kinematics = kinematics or ArmKinematics.from_urdf(urdf)
        self.padding = float(padding)
        # OMPL planners that grow roadmaps in a second thread (PRM) check states
        # concurrently; one pybullet client holds one configuration at a time.
        self._lock = threading.RLock()
        #: Largest motion of any robot point between two checked samples of a
        #: segment [m]: the padding, so that sampled checks are conservative.
        self.max_step = self.padding if self.padding > 0 else 0.005
        self._lower = [float(v) - 1e-9 for v in self.kinematics.lower]
        self._upper = [float(v) + 1e-9 for v in self.kinematics.upper]
        self._client = pybullet.connect(pybullet.DIRECT)
        c = self._client
        try:
            path = str(self.kinematics.urdf.path if urdf is None else urdf)
            self._robot = pybullet.loadURDF(
                path,
                useFixedBase=True,
                # Exact cylinders (the wheels), as the simulator loads them.
                flags=pybullet.URDF_USE_SELF_COLLISION | pybullet.URDF_USE_IMPLICIT_CYLINDER,
                physicsClientId=c,
            )
            self._index_links()
            if self.kinematics.root != self._link_names[-1]:
                raise SceneError(
                    f"the scene works in the URDF root frame {self._link_names[-1]!r}; "
                    f"build its kinematics with root={self._link_names[-1]!r}, not {self.kinematics.root!r}"
                )
            self._obstacles: dict[str, Obstacle] = {}
            self._bodies: dict[str, int] = {}
            self._body_names: dict[int, str] = {}
            self._attached: dict[str, tuple[int, np.ndarray]] = {}  # name -> (link, link->object (4, 4))
            for name, value in (fixed_joints or {}).items():
                self.set_fixed_joint(name, value)
            self._reach_links = self._link_reach()
            self._reach = self._reach_from(self._reach_links)
            self._always = self._always_colliding(acm_samples, seed)
            self._filter_self_pairs()
            if floor:
                self.add_box(_FLOOR, (20.0, 20.0, 0.1), (0.0, 0.0, -0.05))
        except BaseException:
            pybullet.disconnect(physicsClientId=c)
            raise

    # ------------------------------------------------------------- robot model
    def _index_links(self) -> None:
        c, rid = self._client, self._robot
        n = pybullet.getNumJoints(rid, physicsClientId=c)
        infos = [pybullet.getJointInfo(rid, i, physicsClientId=c) for i in range(n)]
        self._joint_index = {info[1].decode(): i for i, info in enumerate(infos)}
        self._link_names = {-1: pybullet.getBodyInfo(rid, physicsClientId=c)[0].decode()}
        self._link_names.update({i: info[12].decode() for i, info in enumerate(infos)})
        self._link_index = {name: i for i, name in self._link_names.items()}
        self._arm_index = []
        for name in self.kinematics.joint_names:
            if name not in self._joint_index:
                raise SceneError(f"joint {name!r} not in the pybullet model; joints: {sorted(self._joint_index)}")
            self._arm_index.append(self._joint_index[name])
        self._other_movable = {
            info[1].decode(): i
            for i, info in enumerate(infos)
            if info[2] != pybullet.JOINT_FIXED and i not in self._arm_index
        }
        # Rigid group of each link: the index of the nearest arm joint above it,
        # -1 for links on the base. Links of one group never move relative to
        # each other while the arm plans.
        parent = {i: info[16] for i, info in enumerate(infos)}
        self._group: dict[int, int] = {-1: -1}
        for i in range(n):
            j, group = i, -1
            while j != -1:
                if j in self._arm_index:
                    group = j
                    break
                j = parent[j]
            self._group[i] = group
        self._parent = parent

    def _link_reach(self) -> dict[int, float]:
        """For each arm joint: the farthest collision point of the links it
        carries directly (its rigid group), from the joint origin [m]."""
        c, rid = self._client, self._robot
        self._set_arm(np.zeros(4))
        out = {}
        for j in self._arm_index:
            origin = np.array(pybullet.getLinkState(rid, j, computeForwardKinematics=True, physicsClientId=c)[4])
            far = 0.0
            for link, group in self._group.items():
                if group == j:
                    lo, hi = (np.array(v) for v in pybullet.getAABB(rid, link, physicsClientId=c))
                    if np.all(hi >= lo):
                        corners = np.array(
                            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
                        )
                        far = max(far, float(np.max(np.linalg.norm(corners - origin, axis=1))))
            out[j] = far
        return out

    def _reach_from(self, own: dict[int, float]) -> np.ndarray:
        """Reach of each arm joint over everything it moves, in any configuration
        (triangle inequality along the chain) [m]; (4,)."""
        c, rid = self._client, self._robot
        self._set_arm(np.zeros(4))
        origins = [
            np.array(pybullet.getLinkState(rid, j, computeForwardKinematics=True, physicsClientId=c)[4])
            for j in self._arm_index
        ]
        reach = [0.0] * 4
        for k in range(3, -1, -1):
            reach[k] = own[self._arm_index[k]]
            if k < 3:
                reach[k] = max(reach[k], float(np.linalg.norm(origins[k + 1] - origins[k])) + reach[k + 1])
        return np.array(reach)

    def _update_reach(self) -> None:
        """Reach including attached objects (at the configuration last set)."""
        own = dict(self._reach_links)
        c, rid = self._client, self._robot
        for name, (link, _rel) in self._attached.items():
            j = self._group[link]
            if j == -1:
                continue  # attached to the base: it does not move with the arm
            origin = np.array(pybullet.getLinkState(rid, j, computeForwardKinematics=True, physicsClientId=c)[4])
            lo, hi = (np.array(v) for v in pybullet.getAABB(self._bodies[name], physicsClientId=c))
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
            own[j] = max(own[j], float(np.max(np.linalg.norm(corners - origin, axis=1))))
        self._reach = self._reach_from(own)

    def _filter_self_pairs(self) -> None:
        # Tell Bullet to skip the pairs the ACM ignores: it then does no
        # narrow-phase work for them (the base links resting on each other, the
        # closed fingers touching) and a check costs a few microseconds.
        c, rid = self._client, self._robot
        links = sorted(self._link_names)
        for i, a in enumerate(links):
            for b in links[i + 1 :]:
                if not self._checked_self_pair(a, b) or self._pair(a, b) in self._always:
                    pybullet.setCollisionFilterPair(rid, rid, a, b, 0, physicsClientId=c)

    def _link_name(self, body: int, link: int) -> str:
        if body == self._robot:
            return self._link_names.get(link, f"link#{link}")
        return self._body_names.get(body, f"body#{body}")

    def _always_colliding(self, samples: int, seed: int) -> frozenset[tuple[int, int]]:
        """Self-collision pairs that collide in every sampled configuration."""
        if samples <= 0:
            return frozenset()
        rng = np.random.default_rng(seed)
        k = self.kinematics
        counts: dict[tuple[int, int], int] = {}
        for _ in range(samples):
            self._set_arm(rng.uniform(k.lower, k.upper))
            for pair in {self._pair(*c[3:5]) for c in self._raw_self_contacts()}:
                counts[pair] = counts.get(pair, 0) + 1
        return frozenset(p for p, n in counts.items() if n == samples)

    @staticmethod
    def _pair(a: int, b: int) -> tuple[int, int]:
        return (a, b) if a <= b else (b, a)

    def _checked_self_pair(self, a: int, b: int) -> bool:
        if self._group[a] == self._group[b]:
            return False
        if self._parent.get(a) == b or self._parent.get(b) == a:
            return False
        return True

    def _raw_self_contacts(self) -> list[tuple]:
        pybullet.performCollisionDetection(physicsClientId=self._client)
        return [
            c
            for c in pybullet.getContactPoints(bodyA=self._robot, bodyB=self._robot, physicsClientId=self._client)
            if c[8] < 0.0 and self._checked_self_pair(c[3], c[4])
        ]

    def _set_arm(self, q: JointValues) -> None:
        c, rid = self._client, self._robot
        pybullet.resetJointStatesMultiDof(rid, self._arm_index, [[float(v)] for v in q], physicsClientId=c)
        for name, (link, rel) in self._attached.items():
            state = pybullet.getLinkState(rid, link, computeForwardKinematics=True, physicsClientId=c)
            pose = _pose_matrix(state[4], state[5]) @ rel
            pos, quat = _matrix_pose(pose)
            pybullet.resetBasePositionAndOrientation(self._bodies[name], pos, quat, physicsClientId=c)

    def set_fixed_joint(self, name: str, value: float) -> None:
        """Set a non-arm joint (e.g. ``gripper_left_joint`` [m]) for later checks."""
        if name not in self._other_movable:
            raise SceneError(f"no settable joint {name!r}; choices: {sorted(self._other_movable)}")
        if not math.isfinite(value):
            raise InvalidInputError(f"{name} must be finite, got {value!r}")
        with self._lock:
            pybullet.resetJointState(self._robot, self._other_movable[name], float(value), physicsClientId=self._client)
            if hasattr(self, "_reach_links"):  # after construction: open fingers reach farther
                self._reach_links = self._link_reach()
                self._update_reach()

    # --------------------------------------------------------------- obstacles
    @property
    def obstacles(self) -> dict[str, Obstacle]:
        """The obstacles by name (a copy)."""
        return dict(self._obstacles)

    def has(self, name: str) -> bool:
        """True when an obstacle called ``name`` exists."""
        return name in self._obstacles

    def add_box(
        self,
        name: str,
        size: Sequence[float],
        position: Sequence[float],
        orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
    ) -> Obstacle:
        """Add (or replace) a box of full extents ``size`` [m] centred at ``position`` [m]."""
        return self._add(Obstacle(name, "box", _vec(size, 3, "size"), _vec3(position, "position"), _quat(orientation)))

    def add_cylinder(
        self,
        name: str,
        radius: float,
        height: float,
        position: Sequence[float],
        orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
    ) -> Obstacle:
        """Add (or replace) an upright cylinder (``radius``, ``height`` [m]) centred at ``position`` [m]."""
        return self._add(
            Obstacle(
                name, "cylinder", _vec((radius, height), 2, "size"), _vec3(position, "position"), _quat(orientation)
            )
        )

    def add_sphere(self, name: str, radius: float, position: Sequence[float]) -> Obstacle:
        """Add (or replace) a sphere of ``radius`` [m] centred at ``position`` [m]."""
        return self._add(Obstacle(name, "sphere", _vec((radius,), 1, "size"), _vec3(position, "position")))

    def add(self, obstacle: Obstacle) -> Obstacle:
        """Add (or replace) an :class:`Obstacle` value (world obstacles only)."""
        if obstacle.attached_to is not None:
            raise InvalidInputError("add() takes world obstacles; use attach() after adding")
        return self._add(obstacle)

    def _add(self, ob: Obstacle) -> Obstacle:
        if not ob.name:
            raise InvalidInputError("an obstacle needs a non-empty name")
        if any(v <= 0 for v in ob.size):
            raise InvalidInputError(f"obstacle {ob.name!r}: sizes must be > 0 m, got {ob.size}")
        if ob.name in self._obstacles:
            self.remove(ob.name)
        body = self._create_body(ob)
        self._obstacles[ob.name] = ob
        self._bodies[ob.name] = body
        self._body_names[body] = ob.name
        return ob

    def _create_body(self, ob: Obstacle, attached_link: int | None = None) -> int:
        # World obstacles are static (mass 0) and padded. Attached ones move with
        # the robot: they are not padded, like the links, and get a mass because
        # Bullet computes no contacts between two static bodies (nothing is ever
        # stepped, so the mass has no other effect).
        c = self._client
        pad = self.padding if attached_link is None else 0.0
        mass = 0.0 if attached_link is None else 1.0
        if ob.shape == "box":
            shape = pybullet.createCollisionShape(
                pybullet.GEOM_BOX, halfExtents=[s / 2 + pad for s in ob.size], physicsClientId=c
            )
        elif ob.shape == "cylinder":
            shape = pybullet.createCollisionShape(
                pybullet.GEOM_CYLINDER, radius=ob.size[0] + pad, height=ob.size[1] + 2 * pad, physicsClientId=c
            )
        elif ob.shape == "sphere":
            shape = pybullet.createCollisionShape(pybullet.GEOM_SPHERE, radius=ob.size[0] + pad, physicsClientId=c)
        else:
            raise InvalidInputError(f"obstacle {ob.name!r}: shape must be box, cylinder or sphere, got {ob.shape!r}")
        body = pybullet.createMultiBody(
            baseMass=mass,
            baseCollisionShapeIndex=shape,
            basePosition=ob.position,
            baseOrientation=ob.orientation,
            physicsClientId=c,
        )
        # A world obstacle is not checked against the base (the floor touches the
        # wheels); an attached one not against the links it moves rigidly with.
        # Every pair is set, enabled or not: pybullet reuses the ids of removed
        # bodies and keeps pair filters by id.
        ignored = -1 if attached_link is None else self._group[attached_link]
        for link, group in self._group.items():
            enable = 0 if group == ignored else 1
            pybullet.setCollisionFilterPair(self._robot, body, link, -1, enable, physicsClientId=c)
        return body

    def _replace_body(self, ob: Obstacle, attached_link: int | None) -> None:
        old = self._bodies[ob.name]
        pybullet.removeBody(old, physicsClientId=self._client)
        del self._body_names[old]
        body = self._create_body(ob, attached_link)
        self._bodies[ob.name] = body
        self._body_names[body] = ob.name

    def remove(self, name: str) -> None:
        """Remove the obstacle ``name`` (world or attached)."""
        if name not in self._obstacles:
            raise SceneError(f"no obstacle {name!r}; obstacles: {sorted(self._obstacles)}")
        body = self._bodies.pop(name)
        pybullet.removeBody(body, physicsClientId=self._client)
        del self._obstacles[name], self._body_names[body]
        if self._attached.pop(name, None) is not None:
            self._update_reach()

    def clear(self, *, keep_floor: bool = True) -> None:
        """Remove every obstacle (but the floor, unless ``keep_floor`` is False)."""
        for name in list(self._obstacles):
            if not (keep_floor and name == _FLOOR):
                self.remove(name)

    def attach(self, name: str, q: JointValues, link: str = "end_effector_link") -> Obstacle:
        """Make obstacle ``name`` move with ``link``, keeping its pose relative to
        the link as it is with the arm at ``q`` [rad] (the grasp configuration).

        An attached object is checked against the world and the robot, except
        the links that never move relative to ``link`` (the gripper).
        """
        if name not in self._obstacles:
            raise SceneError(f"no obstacle {name!r}; obstacles: {sorted(self._obstacles)}")
        if link not in self._link_index or self._link_index[link] < 0:
            raise SceneError(f"cannot attach to {link!r}; links: {sorted(k for k in self._link_index if k)}")
        li = self._link_index[link]
        self._set_arm(self.kinematics.check_joints(q))
        state = pybullet.getLinkState(self._robot, li, computeForwardKinematics=True, physicsClientId=self._client)
        ob = self._obstacles[name]
        rel = np.linalg.inv(_pose_matrix(state[4], state[5])) @ _pose_matrix(ob.position, ob.orientation)
        self._attached[name] = (li, rel)
        new = Obstacle(ob.name, ob.shape, ob.size, ob.position, ob.orientation, link)
        self._obstacles[name] = new
        self._replace_body(new, li)
        self._update_reach()
        return new

    def detach(self, name: str) -> Obstacle:
        """Leave an attached obstacle in the world where it was last placed."""
        if name not in self._attached:
            raise SceneError(f"{name!r} is not attached; attached: {sorted(self._attached)}")
        del self._attached[name]
        pos, quat = pybullet.getBasePositionAndOrientation(self._bodies[name], physicsClientId=self._client)
        ob = self._obstacles[name]
        new = Obstacle(ob.name, ob.shape, ob.size, tuple(pos), tuple(quat), None)
        self._obstacles[name] = new
        self._replace_body(new, None)
        self._update_reach()
        return new

    # ---------------------------------------------------------------- checking
    def _contacts(self) -> list[tuple[str, str, float]]:
        """Forbidden contacts at the configuration last set; (name a, name b, distance)."""
        c, rid = self._client, self._robot
        pybullet.performCollisionDetection(physicsClientId=c)
        found = []
        for pt in pybullet.getContactPoints(bodyA=rid, physicsClientId=c):
            dist = pt[8]
            if dist >= 0.0:
                continue
            a, b = pt[3], pt[4]
            if pt[2] == rid:
                if self._checked_self_pair(a, b) and self._pair(a, b) not in self._always:
                    found.append((self._link_name(rid, a), self._link_name(rid, b), dist))
                continue
            name = self._body_names.get(pt[2])
            if name in self._attached:
                if self._group[a] != self._group[self._attached[name][0]]:
                    found.append((self._link_name(rid, a), name, dist))
            elif self._group[a] != -1:
                found.append((self._link_name(rid, a), self._link_name(pt[2], b), dist))
        for name in self._attached:
            body = self._bodies[name]
            for pt in pybullet.getContactPoints(bodyA=body, physicsClientId=c):
                if pt[2] != rid and pt[8] < 0.0:
                    found.append((name, self._link_name(pt[2], pt[4]), pt[8]))
        return found

    def is_valid(self, q: JointValues) -> bool:
        """True when ``q`` [rad] is inside the joint limits and collision-free."""
        if len(q) != 4:
            return False
        for v, lo, hi in zip(q, self._lower, self._upper):
            if not lo <= v <= hi:  # also False for NaN
                return False
        with self._lock:
            self._set_arm(q)
            return not self._contacts()

    def check(self, q: JointValues) -> CollisionReport:
        """Like :meth:`is_valid`, with the colliding pairs for messages."""
        k = self.kinematics
        arr = k.check_joints(q)
        limits = k.within_limits(arr)
        with self._lock:
            self._set_arm(arr)
            found = self._contacts()
        deepest: dict[tuple[str, str], float] = {}
        for a, b, d in found:
            key = (a, b) if a <= b else (b, a)
            deepest[key] = min(d, deepest.get(key, 0.0))
        contacts = tuple(Contact(a, b, d) for (a, b), d in sorted(deepest.items(), key=lambda kv: kv[1]))
        return CollisionReport(limits and not contacts, limits, contacts)

    def displacement_bound(self, a: JointValues, b: JointValues) -> float:
        """Upper bound on how far any point of the moving links (and attached
        objects) travels along the straight joint segment a -> b [m]."""
        dq = np.abs(np.asarray(b, dtype=float) - np.asarray(a, dtype=float))
        return float(dq @ self._reach)

    def segment_valid(
        self,
        a: JointValues,
        b: JointValues,
        resolution: float = 0.01,
        max_step: float | None = None,
    ) -> bool:
        """True when the straight joint-space segment a -> b [rad] is valid at
        samples no more than ``resolution`` [rad] apart (largest joint step)
        and no more than ``max_step`` [m] apart for any point of the robot
        (default: :attr:`max_step`). Ends included.

        With ``max_step`` <= ``padding``, samples free of the padded obstacles
        imply that the motion in between is free of the real ones.
        """
        qa, qb = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        step = self.max_step if max_step is None else max_step
        n = max(
            1,
            int(math.ceil(float(np.max(np.abs(qb - qa))) / resolution)),
            int(math.ceil(self.displacement_bound(qa, qb) / step)),
        )
        # Check the ends first, then bisect-ish order so collisions are found early.
        order = [n, 0] + list(_van_der_corput_order(n))
        return all(self.is_valid(qa + (qb - qa) * (i / n)) for i in order)

    def path_valid(
        self,
        path: Iterable[JointValues],
        resolution: float = 0.01,
        max_step: float | None = None,
    ) -> bool:
        """True when every segment of ``path`` passes :meth:`segment_valid`."""
        pts = [np.asarray(p, dtype=float) for p in path]
        if len(pts) == 1:
            return self.is_valid(pts[0])
        return all(self.segment_valid(a, b, resolution, max_step) for a, b in zip(pts[:-1], pts[1:]))

    # --------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Disconnect the pybullet client (idempotent)."""
        if self._client is not None and self._client >= 0:
            try:
                pybullet.disconnect(physicsClientId=self._client)
            except pybullet.error:
                pass
            self._client = -1

    def __enter__(self) -> PlanningScene:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:  # best effort; close() is the contract
        try:
            self.close()
        except Exception:
            pass

    def __repr__(self) -> str:
        return f"PlanningScene({self.kinematics.urdf.name!r}, obstacles={sorted(self._obstacles)})"


def _van_der_corput_order(n: int) -> Iterable[int]:
    """Indices 1..n-1, coarse to fine (midpoints first)."""
    seen = {0, n}
    step: float = n
    while step > 1:
        half = step / 2
        i = half
        while i < n:
            j = int(round(i))
            if j not in seen:
                seen.add(j)
                yield j
            i += step
        step = half
    for j in range(1, n):
        if j not in seen:
            yield j


def _vec(values: Sequence[float], n: int, what: str) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be {n} numbers, got {values!r}") from None
    if len(out) != n or not all(math.isfinite(v) for v in out):
        raise InvalidInputError(f"{what} must be {n} finite numbers, got {values!r}")
    return out


def _vec3(values: Sequence[float], what: str) -> tuple[float, float, float]:
    x, y, z = _vec(values, 3, what)
    return x, y, z


def _quat(q: Sequence[float]) -> tuple[float, float, float, float]:
    v = np.array(_vec(q, 4, "orientation (x, y, z, w)"))
    norm = float(np.linalg.norm(v))
    if norm < 1e-9:
        raise InvalidInputError(f"orientation must be a unit quaternion, got {q!r}")
    x, y, z, w = (float(c) for c in v / norm)
    return x, y, z, w


def _pose_matrix(pos: Sequence[float], quat: Sequence[float]) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = np.array(pybullet.getMatrixFromQuaternion(quat)).reshape(3, 3)
    t[:3, 3] = pos
    return t


def _matrix_pose(t: np.ndarray) -> tuple[list[float], list[float]]:
    r = t[:3, :3]
    # Shepperd's method, robust for every rotation.
    tr = np.trace(r)
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2
        w, x, y, z = (r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] > r[2, 2]:
        s = math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2
        w, x, y, z = (r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s
    else:
        s = math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2
        w, x, y, z = (r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s
    return list(t[:3, 3]), [x, y, z, w]
