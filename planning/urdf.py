"""A small URDF reader: links, joints, origins, axes and limits.

Only what kinematics needs is read; geometry stays with pybullet, which loads the
same file for the planning scene. The robot URDF in ``sim/models`` is the single
source of truth: nothing here copies its dimensions.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ModelError

__all__ = [
    "UrdfJoint",
    "UrdfRobot",
    "read_urdf",
    "default_urdf_path",
    "rpy_to_matrix",
    "origin_transform",
]

#: Environment variable that overrides :func:`default_urdf_path`.
URDF_ENV = "ACTORBT_URDF"


def default_urdf_path() -> Path:
    """The robot URDF of this repository (``sim/models/mobile_manipulator.urdf``).

    The file is located relative to this package, so reading it imports nothing
    from ``sim``. ``$ACTORBT_URDF`` overrides it.
    """
    env = os.environ.get(URDF_ENV)
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[1] / "sim" / "models" / "mobile_manipulator.urdf"


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>`` of a URDF.

    Attributes:
        name: joint name.
        type: ``revolute``, ``continuous``, ``prismatic``, ``fixed``, ...
        parent, child: link names.
        xyz: origin translation in the parent link frame [m].
        rpy: origin rotation (roll, pitch, yaw) [rad], fixed axes X-Y-Z.
        axis: unit joint axis in the joint frame.
        lower, upper: position limits [rad or m]; ``-inf``/``inf`` when absent.
        velocity: velocity limit [rad/s or m/s]; ``inf`` when absent.
        effort: effort limit [N m or N]; ``inf`` when absent.
    """

    name: str
    type: str
    parent: str
    child: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower: float
    upper: float
    velocity: float
    effort: float

    @property
    def movable(self) -> bool:
        """True for joints that have a position variable."""
        return self.type in ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class UrdfRobot:
    """The kinematic tree of a URDF: link names and joints keyed by name."""

    name: str
    path: Path
    links: tuple[str, ...]
    joints: dict[str, UrdfJoint]

    def joint(self, name: str) -> UrdfJoint:
        """The joint called ``name``; :class:`ModelError` lists the joints otherwise."""
        try:
            return self.joints[name]
        except KeyError:
            raise ModelError(f"{self.path.name}: no joint {name!r}; joints are {sorted(self.joints)}") from None

    def parent_joint(self, link: str) -> UrdfJoint | None:
        """The joint whose child is ``link``; None for the root link."""
        for j in self.joints.values():
            if j.child == link:
                return j
        return None

    def chain(self, root: str, tip: str) -> list[UrdfJoint]:
        """Joints from ``root`` down to ``tip``, in order from the root."""
        for link in (root, tip):
            if link not in self.links:
                raise ModelError(f"{self.path.name}: no link {link!r}; links are {sorted(self.links)}")
        chain: list[UrdfJoint] = []
        link = tip
        while link != root:
            j = self.parent_joint(link)
            if j is None:
                raise ModelError(f"{self.path.name}: link {tip!r} is not below {root!r}")
            chain.append(j)
            link = j.parent
        chain.reverse()
        return chain


def _floats(text: str | None, default: tuple[float, float, float], what: str) -> tuple[float, float, float]:
    if text is None:
        return default
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        raise ModelError(f"bad numbers {text!r} in {what}") from None
    if len(values) != len(default):
        raise ModelError(f"{what}: expected {len(default)} numbers, got {text!r}")
    x, y, z = values
    return x, y, z


def read_urdf(path: str | os.PathLike[str] | None = None) -> UrdfRobot:
    """Parse a URDF file (default: :func:`default_urdf_path`)."""
    p = Path(path) if path is not None else default_urdf_path()
    try:
        root = ET.parse(p).getroot()
    except FileNotFoundError:
        raise ModelError(f"URDF not found: {p}") from None
    except ET.ParseError as exc:
        raise ModelError(f"{p}: not valid XML: {exc}") from None
    if root.tag != "robot":
        raise ModelError(f"{p}: root element is <{root.tag}>, expected <robot>")
    links = tuple(el.get("name", "") for el in root.findall("link"))
    joints: dict[str, UrdfJoint] = {}
    for el in root.findall("joint"):
        name = el.get("name", "")
        what = f"{p.name} joint {name!r}"
        origin = el.find("origin")
        axis_el = el.find("axis")
        limit = el.find("limit")
        parent, child = el.find("parent"), el.find("child")
        if parent is None or child is None:
            raise ModelError(f"{what}: needs <parent> and <child>")
        axis = _floats(axis_el.get("xyz") if axis_el is not None else None, (1.0, 0.0, 0.0), what)
        norm = math.sqrt(sum(a * a for a in axis))
        if norm == 0.0:
            raise ModelError(f"{what}: zero axis")
        jtype = el.get("type", "fixed")
        lower, upper = -math.inf, math.inf
        velocity = effort = math.inf
        if limit is not None:
            velocity = float(limit.get("velocity", "inf"))
            effort = float(limit.get("effort", "inf"))
            if jtype != "continuous":
                lower = float(limit.get("lower", "0"))
                upper = float(limit.get("upper", "0"))
        joints[name] = UrdfJoint(
            name=name,
            type=jtype,
            parent=parent.get("link", ""),
            child=child.get("link", ""),
            xyz=_floats(origin.get("xyz") if origin is not None else None, (0.0, 0.0, 0.0), what),
            rpy=_floats(origin.get("rpy") if origin is not None else None, (0.0, 0.0, 0.0), what),
            axis=(axis[0] / norm, axis[1] / norm, axis[2] / norm),
            lower=lower,
            upper=upper,
            velocity=velocity,
            effort=effort,
        )
    return UrdfRobot(name=root.get("name", ""), path=p, links=links, joints=joints)


def rpy_to_matrix(rpy: tuple[float, float, float]) -> np.ndarray:
    """Rotation matrix (3, 3) of URDF roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def origin_transform(joint: UrdfJoint) -> np.ndarray:
    """Homogeneous transform (4, 4) from the parent link frame to the joint frame."""
    t = np.eye(4)
    t[:3, :3] = rpy_to_matrix(joint.rpy)
    t[:3, 3] = joint.xyz
    return t
