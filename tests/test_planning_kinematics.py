"""planning.urdf and planning.kinematics: the model read from the URDF, FK and analytic IK."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pybullet
import pytest

from planning import (
    ArmKinematics,
    FailureReason,
    InvalidInputError,
    ModelError,
    UnreachableError,
    default_urdf_path,
    read_urdf,
)
from planning.urdf import origin_transform

ARM = ("joint1", "joint2", "joint3", "joint4")


@pytest.fixture(scope="module")
def kin() -> ArmKinematics:
    return ArmKinematics.from_urdf()


@pytest.fixture(scope="module")
def bullet():
    """The same URDF in pybullet, as an independent FK reference."""
    cid = pybullet.connect(pybullet.DIRECT)
    body = pybullet.loadURDF(str(default_urdf_path()), useFixedBase=True, physicsClientId=cid)
    n = pybullet.getNumJoints(body, physicsClientId=cid)
    infos = [pybullet.getJointInfo(body, i, physicsClientId=cid) for i in range(n)]
    joints = {info[1].decode(): i for i, info in enumerate(infos)}
    links = {info[12].decode(): i for i, info in enumerate(infos)}
    yield cid, body, joints, links, infos
    pybullet.disconnect(physicsClientId=cid)


def test_model_is_read_from_the_urdf(kin, bullet):
    cid, body, joints, links, infos = bullet
    assert kin.joint_names == ARM
    assert kin.root == "base_footprint" and kin.tip == "end_effector_link"
    for k, name in enumerate(ARM):
        info = infos[joints[name]]
        assert kin.lower[k] == pytest.approx(info[8])
        assert kin.upper[k] == pytest.approx(info[9])
        assert kin.max_velocity[k] == pytest.approx(info[11])


def test_fk_matches_pybullet(kin, bullet):
    cid, body, joints, links, _ = bullet
    rng = np.random.default_rng(7)
    for _ in range(50):
        q = rng.uniform(kin.lower, kin.upper)
        for name, v in zip(ARM, q):
            pybullet.resetJointState(body, joints[name], float(v), physicsClientId=cid)
        state = pybullet.getLinkState(
            body, links["end_effector_link"], computeForwardKinematics=True, physicsClientId=cid
        )
        t = kin.fk(q)
        assert np.allclose(t[:3, 3], state[4], atol=1e-6)
        rot = np.array(pybullet.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        assert np.allclose(t[:3, :3], rot, atol=1e-6)


def _pose_error(kin, q, pose) -> tuple[float, float]:
    got = kin.fk_pose(q)
    return math.dist((got.x, got.y, got.z), (pose.x, pose.y, pose.z)), abs(got.pitch - pose.pitch)


def test_ik_round_trips_fk_over_random_reachable_poses(kin):
    rng = np.random.default_rng(42)
    for _ in range(500):
        q = rng.uniform(kin.lower, kin.upper)
        pose = kin.fk_pose(q)
        result = kin.ik(pose.x, pose.y, pose.z, pose.pitch, seed=q, heading="any")
        assert result.ok, result.message
        for sol in result.solutions:
            assert kin.within_limits(sol.q)
            pos_err, pitch_err = _pose_error(kin, sol.q, pose)
            assert pos_err < 1e-3 and pitch_err < 1e-6
        # the generating configuration is among the solutions, nearest to its seed
        assert np.allclose(result.solutions[0].q, q, atol=1e-6)


def _joint1_axis_xy() -> np.ndarray:
    robot = read_urdf()
    t = np.eye(4)
    for joint in robot.chain("base_footprint", robot.joint("joint1").child):
        t = t @ origin_transform(joint)
    return t[:2, 3]


def test_ik_round_trips_pick_like_poses_with_outward_heading(kin):
    axis_xy = _joint1_axis_xy()
    rng = np.random.default_rng(3)
    solved = 0
    for _ in range(300):
        x, y, z = rng.uniform(0.10, 0.33), rng.uniform(-0.25, 0.25), rng.uniform(0.02, 0.30)
        pitch = rng.uniform(0.0, math.pi / 2)
        result = kin.ik(x, y, z, pitch)
        if not result.ok:
            assert result.failure is FailureReason.UNREACHABLE and "unreachable" in result.message
            continue
        solved += 1
        for sol in result.solutions:
            assert sol.outward
            got = kin.fk_pose(sol.q)
            assert math.dist((got.x, got.y, got.z), (x, y, z)) < 1e-3
            assert got.pitch == pytest.approx(pitch, abs=1e-6)
            # the tool points away from the arm axis, seen from above
            tool_x = kin.fk(sol.q)[:3, 0]
            radial = np.array([x, y]) - axis_xy
            assert tool_x[:2] @ radial >= -1e-9
    assert solved > 150


def test_ik_returns_every_solution_in_the_limits(kin):
    # Near full extension both elbows fit joint3's limits (OpenManipulator-X's
    # joint3 lower limit rules out elbow-down for most poses).
    result = kin.ik(0.321, 0.0, 0.332, -0.244)
    assert {s.elbow for s in result.solutions if not s.reversed} == {"up", "down"}
    # sorted by distance to the (default zero) seed
    dists = [float(np.linalg.norm(s.q)) for s in result.solutions]
    assert dists == sorted(dists)
    # reaching back over the shoulder (joint1 turned by pi) is a solution too
    over = kin.ik(0.3, 0.0, 0.323, 0.059)
    assert any(s.reversed for s in over.solutions) and any(not s.reversed for s in over.solutions)
    for sol in over.solutions:
        got = kin.fk_pose(sol.q)
        assert math.dist((got.x, got.y, got.z), (0.3, 0.0, 0.323)) < 1e-6


def test_unreachable_pose_is_a_clear_failure(kin):
    result = kin.ik(1.5, 0.0, 0.2, 0.0)
    assert not result.ok
    assert result.failure is FailureReason.UNREACHABLE
    assert "unreachable" in result.message and "reach" in result.message
    with pytest.raises(UnreachableError):
        result.raise_for_failure()
    with pytest.raises(UnreachableError):
        kin.ik_or_raise(1.5, 0.0, 0.2, 0.0)
    with pytest.raises(UnreachableError):
        _ = result.best


def test_bad_ik_input_is_reported(kin):
    assert kin.ik(math.nan, 0, 0, 0).failure is FailureReason.INVALID_INPUT
    assert kin.ik(0.2, 0, 0.1, 0, heading="sideways").failure is FailureReason.INVALID_INPUT  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError):
        kin.fk([0.0, 0.0])


def test_model_errors_name_the_problem(tmp_path):
    with pytest.raises(ModelError, match="no link 'nope'"):
        ArmKinematics.from_urdf(root="nope")
    with pytest.raises(ModelError, match="URDF not found"):
        read_urdf(tmp_path / "missing.urdf")
    # joint3 turned about x: no longer three parallel pitch joints
    tree = ET.parse(default_urdf_path())
    for joint in tree.getroot().findall("joint"):
        if joint.get("name") == "joint3":
            joint.find("axis").set("xyz", "1 0 0")
    bad = tmp_path / "bad.urdf"
    tree.write(bad)
    with pytest.raises(ModelError, match="joint3 axis is not parallel"):
        ArmKinematics.from_urdf(bad)
