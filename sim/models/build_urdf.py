"""Generate sim/models/mobile_manipulator.urdf from primitives.

The URDF file is the single source of truth that the simulator and the planner load;
this script only exists so that inertias are computed rather than typed by hand.
Run:  python -m sim.models.build_urdf   (rewrites the URDF next to this file)

Dimensions (metres) follow the public specs:
  TurtleBot3 Waffle Pi: 281 x 306 x 141 mm, wheel radius 0.033, wheel separation 0.287,
    two rear ball casters, base_link 0.010 above the floor (as in turtlebot3_description).
  OpenManipulator-X (ROBOTIS open_manipulator_x.urdf): link1->joint1 0.012 fwd + 0.017 up,
    joint1->joint2 0.0595 up (shoulder 0.077), joint2->joint3 (0.024, 0.128) (upper arm 0.130),
    joint3->joint4 0.124 (forearm), joint4->end_effector 0.126; limits joint1 +-pi,
    joint2 +-1.5, joint3 [-1.5, 1.4], joint4 [-1.7, 1.97]; 4.8 rad/s.
Deviations, on purpose:
  * The gripper is widened: each finger strokes 0..45 mm (opening 0..90 mm) instead of
    OpenManipulator-X's ~20..75 mm, so a 66 mm can and a 70 mm bottle body fit with margin.
  * The arm base sits 35 mm behind the wheel axle (turtlebot3_manipulation mounts it 92 mm
    behind), so a horizontal grasp reaches a can standing on the floor 0.22-0.30 m ahead of
    base_link and a top-down grasp reaches the floor 0.10-0.22 m ahead.
  * Effort limits are the XM430-W350 stall torque (4.1 N m) rather than ROBOTIS' placeholder.
  * The LDS-01 turret sits at the back of the top plate (x -0.150), behind the arm, so
    base_scan (the laser's frame, x forward) is at (-0.150, 0, 0.122) in base_link: the
    Waffle Pi's 0.122 height (a scan plane 0.132 m above the floor), but not its x (-0.064,
    or -0.024 in turtlebot3_waffle_pi_for_open_manipulator), where the arm base is here.
"""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "mobile_manipulator.urdf"

# ---- key dimensions -------------------------------------------------------------------
BASE_Z = 0.010  # base_footprint -> base_link
WHEEL_R = 0.033
WHEEL_SEP = 0.287
WHEEL_W = 0.018
BASE_X = (-0.205, 0.076)  # chassis extent along x in base_link (281 mm)
BASE_W = 0.306
CHASSIS_Z = (0.005, 0.091)  # chassis box in base_link z (top plate 0.101 above the floor)
LDS = dict(x=-0.150, r=0.035, h=0.040)  # lidar turret on the top plate -> 141 mm overall
IMU_Z = 0.068  # base_link -> imu_link, as in turtlebot3_waffle_pi.urdf.xacro (Jazzy)
SCAN_Z = 0.122  # base_link -> base_scan (the laser plane), as in turtlebot3_waffle_pi.urdf
ARM_X = -0.035  # arm base (link1) origin on the top plate
CASTER = dict(x=-0.177, y=0.064, r=0.010)
CAM = dict(x=0.077, z=0.084, pitch=math.radians(15.0))  # camera_link in base_link
FINGER_STROKE = 0.045
FINGER_X = 0.080  # finger joint origin on link5
EE_X = 0.126


def box_inertia(m, sx, sy, sz):
    return (m * (sy * sy + sz * sz) / 12, m * (sx * sx + sz * sz) / 12, m * (sx * sx + sy * sy) / 12)


def cyl_inertia(m, r, h):  # axis z
    a = m * (3 * r * r + h * h) / 12
    return (a, a, m * r * r / 2)


def sphere_inertia(m, r):
    a = 2 * m * r * r / 5
    return (a, a, a)


def f(v):
    return f"{v:.6g}"


def xyz(v):
    return " ".join(f(x) for x in v)


COLORS = {
    "dark": "0.25 0.25 0.27 1",
    "grey": "0.55 0.55 0.58 1",
    "black": "0.08 0.08 0.08 1",
    "white": "0.9 0.9 0.9 1",
    "blue": "0.15 0.3 0.7 1",
    "pad": "0.9 0.55 0.1 1",
}


def geom(shape):
    kind = shape[0]
    if kind == "box":
        return f'<box size="{xyz(shape[1])}"/>'
    if kind == "cyl":
        return f'<cylinder radius="{f(shape[1])}" length="{f(shape[2])}"/>'
    if kind == "sphere":
        return f'<sphere radius="{f(shape[1])}"/>'
    raise ValueError(kind)


def link(name, mass=None, com=(0, 0, 0), inertia=None, shapes=(), color="dark", friction=None, comment=None):
    """shapes: list of (geometry tuple, origin xyz, origin rpy). Visual == collision."""
    out = []
    if comment:
        out.append(f"  <!-- {comment} -->")
    out.append(f'  <link name="{name}">')
    if mass is not None:
        ixx, iyy, izz = inertia
        out.append("    <inertial>")
        out.append(f'      <origin xyz="{xyz(com)}" rpy="0 0 0"/>')
        out.append(f'      <mass value="{f(mass)}"/>')
        out.append(f'      <inertia ixx="{f(ixx)}" ixy="0" ixz="0" iyy="{f(iyy)}" iyz="0" izz="{f(izz)}"/>')
        out.append("    </inertial>")
    for g, o, r in shapes:
        for tag in ("visual", "collision"):
            out.append(f"    <{tag}>")
            out.append(f'      <origin xyz="{xyz(o)}" rpy="{xyz(r)}"/>')
            out.append(f"      <geometry>{geom(g)}</geometry>")
            if tag == "visual":
                out.append(f'      <material name="{color}"><color rgba="{COLORS[color]}"/></material>')
            out.append(f"    </{tag}>")
    if friction is not None:
        lat, roll, spin = friction
        out.append("    <contact>")
        out.append(f'      <lateral_friction value="{f(lat)}"/>')
        out.append(f'      <rolling_friction value="{f(roll)}"/>')
        out.append(f'      <spinning_friction value="{f(spin)}"/>')
        out.append("    </contact>")
    out.append("  </link>")
    return "\n".join(out)


def joint(name, kind, parent, child, o=(0, 0, 0), r=(0, 0, 0), axis=None, limit=None, damping=None):
    out = [
        f'  <joint name="{name}" type="{kind}">',
        f'    <parent link="{parent}"/>',
        f'    <child link="{child}"/>',
        f'    <origin xyz="{xyz(o)}" rpy="{xyz(r)}"/>',
    ]
    if axis is not None:
        out.append(f'    <axis xyz="{xyz(axis)}"/>')
    if limit is not None:
        lo, hi, eff, vel = limit
        if kind == "continuous":
            out.append(f'    <limit effort="{f(eff)}" velocity="{f(vel)}"/>')
        else:
            out.append(f'    <limit lower="{f(lo)}" upper="{f(hi)}" effort="{f(eff)}" velocity="{f(vel)}"/>')
    if damping is not None:
        out.append(f'    <dynamics damping="{f(damping)}" friction="0"/>')
    out.append("  </joint>")
    return "\n".join(out)


FRAME = dict(mass=1e-4, inertia=(1e-8, 1e-8, 1e-8))  # pure frames: tiny mass, no geometry
# a massless frame on a fixed joint adds nothing to its parent: the dynamics stay bit-identical
# (pybullet gives a link without <inertial> 1 kg, so the zero mass is written out)
MASSLESS = dict(mass=0.0, inertia=(0.0, 0.0, 0.0))


def build() -> str:
    parts = [
        '<?xml version="1.0"?>',
        "<!-- GENERATED by sim/models/build_urdf.py: edit that file, then run",
        "     `python -m sim.models.build_urdf`. See its docstring for dimensions. -->",
        '<robot name="mobile_manipulator">',
    ]
    P = parts.append

    # ---------------- base ----------------
    P(link("base_footprint", **FRAME, comment="ground projection of the wheel axle centre"))
    P(joint("base_joint", "fixed", "base_footprint", "base_link", o=(0, 0, BASE_Z)))
    cx = (BASE_X[0] + BASE_X[1]) / 2
    sx = BASE_X[1] - BASE_X[0]
    cz = (CHASSIS_Z[0] + CHASSIS_Z[1]) / 2
    sz = CHASSIS_Z[1] - CHASSIS_Z[0]
    m_ch, m_lds = 1.30, 0.13
    ich = box_inertia(m_ch, sx, BASE_W, sz)
    lds_z = CHASSIS_Z[1] + LDS["h"] / 2
    ild = cyl_inertia(m_lds, LDS["r"], LDS["h"])
    # combined inertia about combined COM (parallel axis, diagonal approximation)
    m_b = m_ch + m_lds
    com = ((m_ch * cx + m_lds * LDS["x"]) / m_b, 0, (m_ch * cz + m_lds * lds_z) / m_b)

    def shifted(i, m, p):
        dx, dz = p[0] - com[0], p[2] - com[2]
        return (i[0] + m * dz * dz, i[1] + m * (dx * dx + dz * dz), i[2] + m * dx * dx)

    a = shifted(ich, m_ch, (cx, 0, cz))
    b = shifted(ild, m_lds, (LDS["x"], 0, lds_z))
    P(
        link(
            "base_link",
            m_b,
            com,
            tuple(x + y for x, y in zip(a, b)),
            [
                (("box", (sx, BASE_W, sz)), (cx, 0, cz), (0, 0, 0)),
                (("cyl", LDS["r"], LDS["h"]), (LDS["x"], 0, lds_z), (0, 0, 0)),
            ],
            color="dark",
            comment="TurtleBot3 Waffle Pi chassis 281x306 mm + LDS turret (141 mm overall)",
        )
    )

    for side, s in (("left", 1), ("right", -1)):
        m_w = 0.05
        P(
            link(
                f"wheel_{side}_link",
                m_w,
                (0, 0, 0),
                cyl_inertia(m_w, WHEEL_R, WHEEL_W),
                [(("cyl", WHEEL_R, WHEEL_W), (0, 0, 0), (0, 0, 0))],
                color="black",
                friction=(1.0, 0.0, 0.005),
            )
        )
        P(
            joint(
                f"wheel_{side}_joint",
                "continuous",
                "base_link",
                f"wheel_{side}_link",
                o=(0, s * WHEEL_SEP / 2, WHEEL_R - BASE_Z),
                r=(-math.pi / 2, 0, 0),
                axis=(0, 0, 1),
                limit=(0, 0, 4.1, 6.5),
                damping=0.0,
            )
        )
    for side, s in (("left", 1), ("right", -1)):
        m_c = 0.01
        P(
            link(
                f"caster_back_{side}_link",
                m_c,
                (0, 0, 0),
                sphere_inertia(m_c, CASTER["r"]),
                [(("sphere", CASTER["r"]), (0, 0, 0), (0, 0, 0))],
                color="grey",
                friction=(0.02, 0.0, 0.0),
                comment="ball caster: low friction stands in for rolling resistance",
            )
        )
        P(
            joint(
                f"caster_back_{side}_joint",
                "fixed",
                "base_link",
                f"caster_back_{side}_link",
                o=(CASTER["x"], s * CASTER["y"], CASTER["r"] - BASE_Z),
            )
        )

    # ---------------- camera ----------------
    m_cam = 0.072
    P(
        link(
            "camera_link",
            m_cam,
            (0, 0, 0),
            box_inertia(m_cam, 0.025, 0.090, 0.025),
            [(("box", (0.025, 0.090, 0.025)), (0, 0, 0), (0, 0, 0))],
            color="grey",
            comment="RGB-D camera body (RealSense D435-sized), x forward",
        )
    )
    P(joint("camera_joint", "fixed", "base_link", "camera_link", o=(CAM["x"], 0, CAM["z"]), r=(0, CAM["pitch"], 0)))
    P(link("camera_optical_frame", **FRAME, comment="z forward, x right, y down"))
    P(
        joint(
            "camera_optical_joint",
            "fixed",
            "camera_link",
            "camera_optical_frame",
            o=(0.0125, 0, 0),
            r=(-math.pi / 2, 0, -math.pi / 2),
        )
    )

    # ---------------- arm (OpenManipulator-X) ----------------
    top = CHASSIS_Z[1]
    m1 = 0.079
    P(
        link(
            "link1",
            m1,
            (0, 0, 0.0085),
            box_inertia(m1, 0.06, 0.05, 0.017),
            [(("box", (0.06, 0.05, 0.017)), (0.006, 0, 0.0085), (0, 0, 0))],
            color="grey",
            comment="OpenManipulator-X base plate",
        )
    )
    P(joint("arm_base_joint", "fixed", "base_link", "link1", o=(ARM_X, 0, top)))
    m2 = 0.098
    P(
        link(
            "link2",
            m2,
            (0, 0, 0.03),
            box_inertia(m2, 0.034, 0.046, 0.060),
            [(("box", (0.034, 0.046, 0.060)), (0, 0, 0.030), (0, 0, 0))],
            color="dark",
        )
    )
    P(
        joint(
            "joint1",
            "revolute",
            "link1",
            "link2",
            o=(0.012, 0, 0.017),
            axis=(0, 0, 1),
            limit=(-math.pi, math.pi, 4.1, 4.8),
            damping=0.1,
        )
    )
    m3 = 0.138
    ang = math.atan2(0.024, 0.128)
    L3 = math.hypot(0.024, 0.128)
    i3 = box_inertia(m3, 0.028, 0.034, L3)
    P(
        link(
            "link3",
            m3,
            (0.012, 0, 0.064),
            i3,
            [(("box", (0.028, 0.034, L3 + 0.02)), (0.012, 0, 0.064), (0, ang, 0))],
            color="white",
            comment="upper arm, 0.130 incl. 0.024 offset",
        )
    )
    P(
        joint(
            "joint2",
            "revolute",
            "link2",
            "link3",
            o=(0, 0, 0.0595),
            axis=(0, 1, 0),
            limit=(-1.5, 1.5, 4.1, 4.8),
            damping=0.1,
        )
    )
    m4 = 0.133
    P(
        link(
            "link4",
            m4,
            (0.062, 0, 0),
            box_inertia(m4, 0.124, 0.034, 0.028),
            [(("box", (0.124, 0.034, 0.028)), (0.062, 0, 0), (0, 0, 0))],
            color="white",
            comment="forearm 0.124",
        )
    )
    P(
        joint(
            "joint3",
            "revolute",
            "link3",
            "link4",
            o=(0.024, 0, 0.128),
            axis=(0, 1, 0),
            limit=(-1.5, 1.4, 4.1, 4.8),
            damping=0.1,
        )
    )
    m5 = 0.19
    P(
        link(
            "link5",
            m5,
            (0.045, 0, 0),
            box_inertia(m5, 0.08, 0.12, 0.034),
            [
                (("box", (0.060, 0.034, 0.034)), (0.030, 0, 0), (0, 0, 0)),
                (("box", (0.016, 0.120, 0.024)), (FINGER_X - 0.008, 0, 0), (0, 0, 0)),
            ],
            color="dark",
            comment="wrist servo + widened gripper rail (0.12 m)",
        )
    )
    P(
        joint(
            "joint4",
            "revolute",
            "link4",
            "link5",
            o=(0.124, 0, 0),
            axis=(0, 1, 0),
            limit=(-1.7, 1.97, 4.1, 4.8),
            damping=0.1,
        )
    )

    # ---------------- gripper ----------------
    fl = 0.070
    for side, s in (("left", 1), ("right", -1)):
        m_f = 0.02
        P(
            link(
                f"gripper_{side}_link",
                m_f,
                (fl / 2, s * 0.005, 0),
                box_inertia(m_f, fl, 0.010, 0.030),
                [(("box", (fl, 0.010, 0.030)), (fl / 2, s * 0.005, 0), (0, 0, 0))],
                color="pad",
                friction=(2.0, 0.0, 0.02),  # spinning: the pad's contact patch (~15 mm across) resists twisting
                comment=f"{side} finger; inner face at y=0 when the joint is 0 (opening = left + right)",
            )
        )
        P(
            joint(
                f"gripper_{side}_joint",
                "prismatic",
                "link5",
                f"gripper_{side}_link",
                o=(FINGER_X, 0, 0),
                axis=(0, s, 0),
                limit=(0.0, FINGER_STROKE, 15.0, 0.1),
                damping=1.0,
            )
        )
    P(link("end_effector_link", **FRAME, comment="between the fingertips"))
    P(joint("end_effector_joint", "fixed", "link5", "end_effector_link", o=(EE_X, 0, 0)))

    # ---------------- lidar ----------------
    # last in the file, so the other links keep their pybullet indices
    P(link("base_scan", **MASSLESS, comment="LDS-01 laser frame: x forward, beams counter-clockwise from x"))
    P(joint("scan_joint", "fixed", "base_link", "base_scan", o=(LDS["x"], 0, SCAN_Z)))
    # the OpenCR's IMU, where turtlebot3_manipulation_description puts it (/imu's frame_id)
    P(link("imu_link", **MASSLESS, comment="the OpenCR board's IMU"))
    P(joint("imu_joint", "fixed", "base_link", "imu_link", o=(0, 0, IMU_Z)))

    parts.append("</robot>")
    return "\n".join(parts) + "\n"


def main():
    OUT.write_text(build())
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
