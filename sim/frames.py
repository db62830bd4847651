"""The robot's coordinate frames, as /tf and /tf_static carry them (REP 105).

    map --(a localiser)--> odom --(wheel odometry)--> base_footprint --(URDF)--> base_link
        base_link -> base_scan (lidar), camera_link -> camera_optical_frame,
        wheel_*_link, caster_*, link1 -> link2 .. link5 -> gripper_*_link, end_effector_link

This module gives each edge as a :class:`Transform`, from the same sources the topics use;
sim/topics.py wraps them in tf2_msgs/TFMessage (the simulator never publishes map -> odom):

* :func:`static_transforms`: every fixed joint of the URDF (robot_state_publisher's
  /tf_static);
* :func:`joint_transforms`: the movable joints at given positions (what
  robot_state_publisher makes of /joint_states);
* :func:`odom_transform`: odom -> base_footprint from :class:`sim.odometry.WheelOdometry`
  (the /odom message carries the same pose).

The URDF (``sim/models/mobile_manipulator.urdf``) is the only source of the dimensions.
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from .robot import URDF

ODOM_FRAME = "odom"
BASE_FRAME = "base_footprint"


@dataclass(frozen=True)
class Transform:
    """``child``'s pose in ``parent``: translation (x, y, z) [m], rotation (x, y, z, w)."""

    parent: str
    child: str
    translation: tuple
    rotation: tuple


@dataclass(frozen=True)
class Joint:
    name: str
    type: str
    parent: str
    child: str
    xyz: tuple
    rpy: tuple
    axis: tuple


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> tuple:
    """URDF rpy (fixed axes X, then Y, then Z) -> quaternion (x, y, z, w)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def quat_mul(a, b) -> tuple:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def quat_rotate(q, v) -> tuple:
    x, y, z, w = q
    # v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    cx, cy, cz = y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]
    return (
        v[0] + 2 * (w * cx + y * cz - z * cy),
        v[1] + 2 * (w * cy + z * cx - x * cz),
        v[2] + 2 * (w * cz + x * cy - y * cx),
    )


def compose(a: Transform, b: Transform) -> Transform:
    """``a`` (p -> q) then ``b`` (q -> r): p -> r."""
    t = quat_rotate(a.rotation, b.translation)
    return Transform(
        a.parent, b.child, tuple(x + y for x, y in zip(a.translation, t)), quat_mul(a.rotation, b.rotation)
    )


def _floats(text, n, default):
    return tuple(float(x) for x in text.split()) if text else (default,) * n


@functools.lru_cache(maxsize=4)
def urdf_joints(path: str | Path = URDF) -> tuple[Joint, ...]:
    """The URDF's joints, in file order."""
    out = []
    for j in ET.parse(path).getroot().iter("joint"):
        o = j.find("origin")
        a = j.find("axis")
        parent, child = j.find("parent"), j.find("child")
        name, jtype = j.get("name"), j.get("type")
        parent_link = parent.get("link") if parent is not None else None
        child_link = child.get("link") if child is not None else None
        if name is None or jtype is None or parent_link is None or child_link is None:
            raise ValueError(f"{path}: joint {name!r} needs a name, a type, a parent link and a child link")
        out.append(
            Joint(
                name,
                jtype,
                parent_link,
                child_link,
                _floats(o.get("xyz") if o is not None else None, 3, 0.0),
                _floats(o.get("rpy") if o is not None else None, 3, 0.0),
                _floats(a.get("xyz"), 3, 0.0) if a is not None else (1.0, 0.0, 0.0),
            )
        )
    return tuple(out)


def _origin(j: Joint) -> Transform:
    return Transform(j.parent, j.child, j.xyz, quat_from_rpy(*j.rpy))


def static_transforms(path: str | Path = URDF) -> list[Transform]:
    """Every fixed joint: base_footprint -> base_link -> base_scan, the camera frames, ..."""
    return [_origin(j) for j in urdf_joints(path) if j.type == "fixed"]


def joint_transforms(positions: dict, path: str | Path = URDF) -> list[Transform]:
    """The movable joints named in ``positions`` (rad or m), e.g. from /joint_states."""
    out = []
    for j in urdf_joints(path):
        if j.type == "fixed" or j.name not in positions:
            continue
        q = float(positions[j.name])
        origin = _origin(j)
        if j.type in ("revolute", "continuous"):
            s = math.sin(q / 2)
            motion = Transform(
                j.child, j.child, (0.0, 0.0, 0.0), (j.axis[0] * s, j.axis[1] * s, j.axis[2] * s, math.cos(q / 2))
            )
        elif j.type == "prismatic":
            motion = Transform(j.child, j.child, tuple(q * a for a in j.axis), (0.0, 0.0, 0.0, 1.0))
        else:
            raise ValueError(f"joint {j.name}: type {j.type} is not handled")
        out.append(compose(origin, motion))
    return out


def odom_transform(odometry) -> Transform:
    """odom -> base_footprint from a WheelOdometry (planar: z 0, yaw only)."""
    yaw = odometry.yaw
    return Transform(
        ODOM_FRAME, BASE_FRAME, (odometry.x, odometry.y, 0.0), (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    )
