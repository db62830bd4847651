"""Forward and analytic inverse kinematics of the 4-DOF arm, read from the URDF.

The arm is a yaw joint followed by three parallel pitch joints (OpenManipulator-X
layout). Inverse kinematics is closed form: the yaw puts the arm plane through the
target, then a planar 3-link problem is solved for the wrist and the tool pitch.
It returns every solution inside the joint limits: elbow up and elbow down, and,
when joint 1 allows it, the "reversed" solutions that reach over the shoulder.

Frames and conventions
----------------------
* Poses are expressed in the model's **root frame**, ``base_footprint`` by
  default (on the floor under the wheel axle centre, x forward, z up). Pass
  ``root="link1"`` (or any link above ``joint1``) for the arm base frame.
* A target pose is ``(x, y, z, pitch)``: the position of ``end_effector_link``
  [m] and the tool pitch [rad], the angle of the tool x axis *below* the
  horizontal (0 = pointing forward, +pi/2 = pointing straight down). The tool
  yaw is set by ``joint1`` and is not a free variable of a 4-DOF arm; by
  default IK keeps the tool pointing away from the joint1 axis (``heading``).
* Joint values follow the URDF axes: for this robot joint2..4 turn about +y,
  so a positive value tips the arm forward and down.

Nothing here copies the robot's dimensions: link offsets, axes and limits come
from the URDF's ``<joint>`` elements.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, TypeAlias

import numpy as np

from .errors import InvalidInputError, ModelError, UnreachableError
from .failure import FailureReason
from .urdf import UrdfRobot, origin_transform, read_urdf

__all__ = ["ArmPose", "IKSolution", "IKResult", "ArmKinematics"]

ARM_JOINTS = ("joint1", "joint2", "joint3", "joint4")
#: joint positions [rad] as callers hold them: a sequence of numbers or an array
JointValues: TypeAlias = Sequence[float] | np.ndarray
_TOL = 1e-6  # geometric tolerance when checking the chain's shape [m] / [rad]
_LIMIT_TOL = 1e-9  # slack on joint limits when checking a given q [rad]
_FIT_TOL = 1e-5  # IK solutions this close outside a limit are clipped onto it [rad]
#                  (URDF limits are often rounded, e.g. 3.14159 for pi)


@dataclass(frozen=True)
class ArmPose:
    """Tool pose of the 4-DOF arm.

    Attributes:
        x, y, z: position of the tool frame (``end_effector_link``) in the
            model root frame [m].
        pitch: angle of the tool x axis below the horizontal [rad]
            (0 = forward, +pi/2 = straight down).
    """

    x: float
    y: float
    z: float
    pitch: float

    def position(self) -> np.ndarray:
        """Position as an array (3,) [m]."""
        return np.array([self.x, self.y, self.z])


@dataclass(frozen=True)
class IKSolution:
    """One inverse-kinematics solution.

    Attributes:
        q: joint positions (joint1..joint4) [rad].
        elbow: ``"up"`` when the elbow (joint3) lies above the line from the
            shoulder (joint2) to the wrist (joint4), else ``"down"``.
        reversed: True when joint1 turned the arm away from the target and the
            arm reaches back over the shoulder.
        outward: True when the tool x axis points away from the joint1 axis
            (seen from above), False when it points back towards it.
    """

    q: tuple[float, ...]
    elbow: Literal["up", "down"]
    reversed: bool
    outward: bool


@dataclass(frozen=True)
class IKResult:
    """All solutions for one target, nearest to the seed first.

    Attributes:
        target: the requested pose.
        solutions: solutions inside the joint limits, sorted by joint distance
            to the seed [rad]; empty when the pose is unreachable.
        failure: None on success, else :attr:`FailureReason.UNREACHABLE` or
            :attr:`FailureReason.INVALID_INPUT`.
        message: why it failed, in words ("" on success).
    """

    target: ArmPose
    solutions: tuple[IKSolution, ...]
    failure: FailureReason | None = None
    message: str = ""

    @property
    def ok(self) -> bool:
        """True when at least one solution exists."""
        return self.failure is None and bool(self.solutions)

    @property
    def best(self) -> tuple[float, ...]:
        """Joint positions of the solution nearest the seed [rad]; raises when none."""
        self.raise_for_failure()
        return self.solutions[0].q

    def raise_for_failure(self) -> None:
        """Raise :class:`UnreachableError` (or :class:`InvalidInputError`) when not ok."""
        if not self.ok:
            reason = self.failure or FailureReason.UNREACHABLE
            raise reason.error_type(self.message or f"no IK solution for {self.target}")


@dataclass(frozen=True)
class _Segment:
    fixed: np.ndarray  # (4, 4) transform from the previous joint frame (or root)
    joint: int | None  # index into the arm joints, None for the final fixed part
    axis: np.ndarray  # (3,) unit axis in the joint frame


@dataclass(frozen=True)
class _Planar:
    """The chain seen from the canonical yaw frame C at q = 0 (see ArmKinematics)."""

    s1: float  # +1 if joint1 turns about +z of the root, -1 if about -z
    s: tuple[float, float, float]  # signs of joints 2..4 about +y of C
    lateral: float  # common y offset of joints 2..4 and the tool in C [m]
    p2: tuple[float, float]  # shoulder (joint2) in the (x, z) plane of C [m]
    links: tuple[tuple[float, float], ...]  # (length [m], angle [rad]) of 2->3, 3->4, 4->tool
    pitch0: float  # tool pitch at q = 0 [rad]


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True, eq=False)  # holds arrays: compared by identity
class ArmKinematics:
    """Kinematic model of the arm chain ``root`` -> ``tip`` of a URDF.

    Build it with :meth:`from_urdf`. Joint arrays are ordered as
    :attr:`joint_names`.

    Attributes:
        urdf: the parsed robot description.
        root, tip: link names; poses are in the ``root`` frame.
        joint_names: the four arm joints.
        lower, upper: position limits (4,) [rad].
        max_velocity: URDF velocity limits (4,) [rad/s] (``inf`` when absent).
    """

    urdf: UrdfRobot
    root: str
    tip: str
    joint_names: tuple[str, ...]
    lower: np.ndarray = field(repr=False)
    upper: np.ndarray = field(repr=False)
    max_velocity: np.ndarray = field(repr=False)
    _segments: tuple[_Segment, ...] = field(repr=False)
    _c_frame: np.ndarray = field(repr=False)  # (4, 4) canonical yaw frame C in the root frame
    _c_inv: np.ndarray = field(repr=False)  # (4, 4) root -> C
    _planar: _Planar = field(repr=False)

    # ---------------------------------------------------------------- building
    @classmethod
    def from_urdf(
        cls,
        urdf: UrdfRobot | str | os.PathLike[str] | None = None,
        *,
        root: str = "base_footprint",
        tip: str = "end_effector_link",
        joint_names: Sequence[str] = ARM_JOINTS,
    ) -> ArmKinematics:
        """Read the chain ``root`` -> ``tip`` from a URDF (default: the repo robot).

        Raises:
            ModelError: missing links or joints, or a chain that is not a yaw
                joint followed by three parallel pitch joints.
        """
        robot = urdf if isinstance(urdf, UrdfRobot) else read_urdf(urdf)
        names = tuple(joint_names)
        if len(names) != 4:
            raise ModelError(f"the arm needs 4 joints, got {names}")
        chain = robot.chain(root, tip)
        movable = [j for j in chain if j.movable]
        if tuple(j.name for j in movable) != names:
            raise ModelError(
                f"movable joints from {root!r} to {tip!r} are {[j.name for j in movable]}, expected {list(names)}"
            )
        for j in movable:
            if j.type == "prismatic":
                raise ModelError(f"arm joint {j.name!r} is prismatic; expected revolute")

        segments: list[_Segment] = []
        acc = np.eye(4)
        for j in chain:
            acc = acc @ origin_transform(j)
            if j.movable:
                segments.append(_Segment(acc, names.index(j.name), np.array(j.axis)))
                acc = np.eye(4)
        segments.append(_Segment(acc, None, np.zeros(3)))

        lower = np.array([j.lower for j in movable], dtype=float)
        upper = np.array([j.upper for j in movable], dtype=float)
        lower = np.where(np.isfinite(lower), lower, -math.pi)
        upper = np.where(np.isfinite(upper), upper, math.pi)
        vmax = np.array([j.velocity for j in movable], dtype=float)
        for arr in (lower, upper, vmax):
            arr.setflags(write=False)

        c_frame, planar = cls._analyse(tuple(segments), robot.name)
        return cls(
            urdf=robot,
            root=root,
            tip=tip,
            joint_names=names,
            lower=lower,
            upper=upper,
            max_velocity=vmax,
            _segments=tuple(segments),
            _c_frame=c_frame,
            _c_inv=np.linalg.inv(c_frame),
            _planar=planar,
        )

    @staticmethod
    def _frames(segments: tuple[_Segment, ...], q: JointValues) -> list[np.ndarray]:
        """Root transforms of the four joint frames (after their rotation) and the tip."""
        t = np.eye(4)
        out = []
        for seg in segments:
            t = t @ seg.fixed
            if seg.joint is not None:
                t = t @ _axis_rotation(seg.axis, q[seg.joint])
            out.append(t)
        return out

    @classmethod
    def _analyse(cls, segments: tuple[_Segment, ...], name: str) -> tuple[np.ndarray, _Planar]:
        """Check the yaw + 3 parallel pitch shape and extract the planar geometry.

        The canonical yaw frame C has its origin at joint1, z along the root's
        +z, y along joint2's axis and x = y cross z, all at q = 0.
        """
        frames = cls._frames(segments, (0.0, 0.0, 0.0, 0.0))
        z = np.array([0.0, 0.0, 1.0])
        a1 = frames[0][:3, :3] @ segments[0].axis
        if abs(abs(a1 @ z) - 1.0) > _TOL:
            raise ModelError(f"{name}: joint1 axis {a1.round(4)} is not vertical in the root frame")
        a2 = frames[1][:3, :3] @ segments[1].axis
        if abs(a2 @ z) > _TOL:
            raise ModelError(f"{name}: joint2 axis {a2.round(4)} is not horizontal")
        y = a2 / np.linalg.norm(a2)
        x = np.cross(y, z)
        c = np.eye(4)
        c[:3, :3] = np.column_stack([x, y, z])
        c[:3, 3] = frames[0][:3, 3]
        c_inv = np.linalg.inv(c)

        signs = []
        for k in (1, 2, 3):
            ak = c_inv[:3, :3] @ frames[k][:3, :3] @ segments[k].axis
            if abs(abs(ak[1]) - 1.0) > _TOL:
                raise ModelError(
                    f"{name}: joint{k + 1} axis is not parallel to joint2's; "
                    "the analytic IK needs three parallel pitch joints"
                )
            signs.append(math.copysign(1.0, ak[1]))
        pts = [(c_inv @ frames[k])[:3, 3] for k in (1, 2, 3, 4)]  # joints 2, 3, 4 and the tip
        lateral = pts[0][1]
        if any(abs(p[1] - lateral) > _TOL for p in pts):
            raise ModelError(f"{name}: joints 2..4 and the tip are not in one plane")
        links = []
        for a, b in zip(pts[:-1], pts[1:]):
            dx, dz = b[0] - a[0], b[2] - a[2]
            links.append((math.hypot(dx, dz), math.atan2(dz, dx)))
        if links[0][0] < _TOL or links[1][0] < _TOL:
            raise ModelError(f"{name}: zero-length upper arm or forearm")
        tool_x = c_inv[:3, :3] @ frames[4][:3, 0]
        if abs(tool_x[1]) > _TOL:
            raise ModelError(f"{name}: the tool x axis leaves the arm plane")
        pitch0 = -math.atan2(tool_x[2], tool_x[0])
        s1 = math.copysign(1.0, a1 @ z)
        planar = _Planar(
            s1=s1,
            s=(signs[0], signs[1], signs[2]),
            lateral=float(lateral),
            p2=(float(pts[0][0]), float(pts[0][2])),
            links=tuple(links),
            pitch0=pitch0,
        )
        return c, planar

    # -------------------------------------------------------------- forward
    def check_joints(self, q: JointValues) -> np.ndarray:
        """``q`` as an array (4,) [rad]; :class:`InvalidInputError` unless 4 finite values."""
        arr = np.asarray(q, dtype=float)
        if arr.shape != (4,) or not np.all(np.isfinite(arr)):
            raise InvalidInputError(f"q must be 4 finite joint positions {self.joint_names}, got {q!r}")
        return arr

    def fk(self, q: JointValues) -> np.ndarray:
        """Transform (4, 4) of the tip frame in the root frame for joints ``q`` [rad]."""
        return self._frames(self._segments, self.check_joints(q))[-1]

    def fk_pose(self, q: JointValues) -> ArmPose:
        """Tool pose (x, y, z [m], pitch [rad]) for joints ``q`` [rad]."""
        t = self.fk(q)
        x_axis = t[:3, 0]
        pitch = -math.atan2(x_axis[2], math.hypot(x_axis[0], x_axis[1]))
        return ArmPose(float(t[0, 3]), float(t[1, 3]), float(t[2, 3]), pitch)

    def within_limits(self, q: JointValues, tol: float = _LIMIT_TOL) -> bool:
        """True when every joint of ``q`` [rad] is inside its limits (+- ``tol``)."""
        arr = self.check_joints(q)
        return bool(np.all(arr >= self.lower - tol) and np.all(arr <= self.upper + tol))

    # -------------------------------------------------------------- inverse
    def _fit_limits(self, k: int, a: float) -> float | None:
        """``a`` or ``a +- 2 pi`` inside joint k's limits, nearest to 0; None if none fits."""
        fits = [
            v
            for v in (a, a - 2 * math.pi, a + 2 * math.pi)
            if self.lower[k] - _FIT_TOL <= v <= self.upper[k] + _FIT_TOL
        ]
        if not fits:
            return None
        v = min(fits, key=abs)
        return float(min(max(v, self.lower[k]), self.upper[k]))

    def ik(
        self,
        x: float,
        y: float,
        z: float,
        pitch: float,
        *,
        seed: JointValues | None = None,
        heading: Literal["outward", "inward", "any"] = "outward",
    ) -> IKResult:
        """Every joint solution that puts the tool at ``(x, y, z)`` [m] with ``pitch`` [rad].

        Args:
            x, y, z: tool position in the root frame [m].
            pitch: tool x axis angle below the horizontal [rad].
            seed: joints [rad] the solutions are sorted by (nearest first), and
                the joint1 value used when the target is on the joint1 axis.
                Default: all zeros.
            heading: which way the tool may point, seen from above:
                ``"outward"`` (away from the joint1 axis, the usual grasp),
                ``"inward"`` (back towards it) or ``"any"``. At pitch +-pi/2
                both headings are the same pose and count as outward.

        Returns:
            An :class:`IKResult`; it never raises for an unreachable pose.
        """
        target = ArmPose(float(x), float(y), float(z), float(pitch))
        if not all(math.isfinite(v) for v in (x, y, z, pitch)):
            return IKResult(target, (), FailureReason.INVALID_INPUT, f"non-finite target {target}")
        try:
            seed_q = np.zeros(4) if seed is None else self.check_joints(seed)
        except InvalidInputError as exc:
            return IKResult(target, (), FailureReason.INVALID_INPUT, str(exc))

        pl = self._planar
        d = self._c_inv @ np.array([x, y, z, 1.0])
        rho = math.hypot(d[0], d[1])
        yaw_options: list[tuple[float, float, bool]] = []  # (psi, radial reach R, reversed)
        if rho < abs(pl.lateral) - _TOL:
            return IKResult(
                target,
                (),
                FailureReason.UNREACHABLE,
                f"{target} is {rho:.4f} m from the joint1 axis, closer than the arm's "
                f"lateral offset {abs(pl.lateral):.4f} m",
            )
        if rho < _TOL and abs(pl.lateral) < _TOL:
            psi = pl.s1 * seed_q[0]
            yaw_options = [(psi, 0.0, False)]
        else:
            radial = math.sqrt(max(rho * rho - pl.lateral**2, 0.0))
            base = math.atan2(d[1], d[0])
            for r, rev in ((radial, False), (-radial, True)):
                yaw_options.append((base - math.atan2(pl.lateral, r), r, rev))

        if heading not in ("outward", "inward", "any"):
            return IKResult(
                target,
                (),
                FailureReason.INVALID_INPUT,
                f"heading must be 'outward', 'inward' or 'any', got {heading!r}",
            )
        # The tool x axis lies in the arm plane at the in-plane angle -phi from the
        # arm's x axis; "pitch below horizontal" is met by phi = pitch (tool along
        # the arm's reach) and phi = pi - pitch (tool pointing back).
        vertical = abs(abs(_wrap(pitch)) - math.pi / 2) < 1e-12
        in_plane = [(pitch, True)] if vertical else [(pitch, True), (math.pi - pitch, False)]
        (l1, b1), (l2, b2), (l3, b3) = pl.links
        solutions: list[IKSolution] = []
        reasons: list[str] = []
        for (psi, r, rev), (tool_angle, along) in ((y, t) for y in yaw_options for t in in_plane):
            outward = along != rev  # the reach points at the target unless reversed
            if vertical:
                outward = True
            if (heading == "outward" and not outward) or (heading == "inward" and outward):
                continue
            phi = tool_angle - pl.pitch0  # = s2 q2 + s3 q3 + s4 q4
            q1 = self._fit_limits(0, _wrap(pl.s1 * psi))
            if q1 is None:
                reasons.append(f"joint1 would be {math.degrees(_wrap(pl.s1 * psi)):.1f} deg")
                continue
            wx = r - l3 * math.cos(b3 - phi) - pl.p2[0]
            wz = d[2] - l3 * math.sin(b3 - phi) - pl.p2[1]
            dist2 = wx * wx + wz * wz
            cos_delta = (dist2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
            if abs(cos_delta) > 1.0 + 1e-9:
                reasons.append(
                    f"wrist {math.sqrt(dist2):.4f} m from the shoulder, reach is {abs(l1 - l2):.4f}..{l1 + l2:.4f} m"
                )
                continue
            cos_delta = min(1.0, max(-1.0, cos_delta))
            base_delta = math.acos(cos_delta)
            for delta in (base_delta, -base_delta) if base_delta > 1e-12 else (0.0,):
                th1 = math.atan2(wz, wx) - math.atan2(l2 * math.sin(delta), l1 + l2 * math.cos(delta))
                th2 = th1 + delta
                u2 = b1 - th1
                u3 = (b2 - th2) - u2
                u4 = phi - u2 - u3
                raw = (pl.s[0] * u2, pl.s[1] * u3, pl.s[2] * u4)
                qs = [q1]
                for k, a in enumerate(raw, start=1):
                    v = self._fit_limits(k, _wrap(a))
                    if v is None:
                        reasons.append(
                            f"{self.joint_names[k]} would be {math.degrees(_wrap(a)):.1f} deg, limits "
                            f"{math.degrees(self.lower[k]):.1f}..{math.degrees(self.upper[k]):.1f} deg"
                        )
                        break
                    qs.append(v)
                else:
                    # Elbow above the shoulder-wrist line, seen with the reach pointing forward.
                    ex, ez = l1 * math.cos(th1), l1 * math.sin(th1)
                    cross = wx * ez - wz * ex
                    up = cross * (1.0 if wx >= 0 else -1.0) > 0
                    solutions.append(IKSolution(tuple(qs), "up" if up else "down", rev, outward))
        if not solutions:
            detail = "; ".join(dict.fromkeys(reasons)) or "no solution"
            return IKResult(target, (), FailureReason.UNREACHABLE, f"{target} is unreachable: {detail}")
        solutions.sort(key=lambda s: float(np.linalg.norm(np.asarray(s.q) - seed_q)))
        return IKResult(target, tuple(solutions))

    def ik_or_raise(
        self,
        x: float,
        y: float,
        z: float,
        pitch: float,
        *,
        seed: JointValues | None = None,
        heading: Literal["outward", "inward", "any"] = "outward",
    ) -> tuple[float, ...]:
        """The solution nearest ``seed`` [rad]; raises :class:`UnreachableError` when none."""
        result = self.ik(x, y, z, pitch, seed=seed, heading=heading)
        if not result.ok:
            raise UnreachableError(result.message)
        return result.solutions[0].q
