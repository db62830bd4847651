"""Objects are recognised by their measured shape, not their colour: house_hard seed
2004's yellow mug (a pybullet_data mesh, a distractor) must not pass the carton's box
fit, and the world's real carton must still be found; seed 2001's red flat box is no
lying can. detect() on rendered frames (depth noise on)."""

import math

import numpy as np
import pytest

from actors.perception import detect, registered_appearances
from bench.bench_perception_hard import _frame, _teleport
from sim import SimWorld
from common.quiet_pybullet import pybullet as p


@pytest.fixture(scope="module")
def world():
    w = SimWorld(None, "house_hard", seed=2004)
    yield w
    w.close()


def _name(world, kind):
    return next(o.name for o in world.spec.objects if o.category == kind and o.support == "floor")


def _look(world, xy, distance, bearing_deg, turn=0.0):
    """detect() from ``distance`` [m] away along ``bearing_deg``, facing it (turned by ``turn``)."""
    a = math.radians(bearing_deg)
    _teleport(world, xy[0] - distance * math.cos(a), xy[1] - distance * math.sin(a), a + turn)
    return detect(_frame(world), registered_appearances())


def _near(dets, xy, tol=0.12):
    return [d for d in dets if math.dist((d["x"], d["y"]), xy) < tol]


def _tip_over(world, name, rpy_deg):
    """Lay the object down in place (as a missed grasp knocks it over), resting on the floor;
    returns the (x, y) of its bounding box's centre."""
    body = world.scene.objects[name]
    pos, _ = p.getBasePositionAndOrientation(body, physicsClientId=world.cid)
    x, y = world.object_poses()[name][:2]
    q = p.getQuaternionFromEuler([math.radians(v) for v in rpy_deg])
    p.resetBasePositionAndOrientation(body, pos, q, physicsClientId=world.cid)
    lo, hi = p.getAABB(body, physicsClientId=world.cid)
    p.resetBasePositionAndOrientation(
        body,
        [pos[0] + x - 0.5 * (lo[0] + hi[0]), pos[1] + y - 0.5 * (lo[1] + hi[1]), pos[2] - lo[2] + 5e-4],
        q,
        physicsClientId=world.cid,
    )
    return x, y


def test_the_standing_mug_is_no_carton_from_close_by(world):
    mug = _name(world, "mug")
    xy = world.object_poses()[mug][:2]
    for distance, bearing in ((0.5, 90), (0.7, 90), (0.9, 113), (1.2, 67)):
        near = _near(_look(world, xy, distance, bearing), xy)
        assert near and all(d["category"] == "unknown" for d in near), (distance, bearing, near)


# Views of the mug knocked over on its side (its handle up) where the box fit took it for
# a standing carton before its faces had to be flat: the curved side fits a rectangle
# within the noise point by point, but bows by centimetres.
TIPPED_VIEWS = [
    (0.5, 100, -0.35),
    (0.5, 100, 0.0),
    (0.5, 100, 0.35),
    (0.7, 100, -0.35),
    (0.7, 100, 0.0),
    (0.9, 100, 0.35),
]


def test_a_tipped_over_mug_is_no_carton():
    world = SimWorld(None, "house_hard", seed=2004)
    try:
        xy = _tip_over(world, _name(world, "mug"), (90, 0, 10))
        for distance, bearing, turn in TIPPED_VIEWS:
            near = _near(_look(world, xy, distance, bearing, turn), xy)
            assert near and all(d["category"] == "unknown" for d in near), (distance, bearing, turn, near)
    finally:
        world.close()


def test_the_real_carton_is_still_found(world):
    carton = _name(world, "carton")
    xy = world.object_poses()[carton][:2]
    for distance, bearing in ((0.45, -60), (0.6, 0), (0.6, 60), (0.8, -30), (1.3, -60)):
        found = [d for d in _near(_look(world, xy, distance, bearing), xy, 0.03) if d["category"] == "carton"]
        assert found and found[0]["pose"] == "lying", (distance, bearing, found)


def test_a_lying_carton_is_found_end_on_and_side_on_from_the_grasp_standoff(world):
    # From 0.35 m, a few pixels' step along a face is within the depth noise: the faces'
    # direction came out at random, and the carton as unknown (house_hard 2039, end on).
    # The grasps come square to it, end on or side on.
    carton = _name(world, "carton")
    pose = world.object_poses()[carton]
    axis = np.array(p.getMatrixFromQuaternion(pose[3:])).reshape(3, 3)[:, 2]  # its 120 mm side
    along = math.degrees(math.atan2(axis[1], axis[0]))
    for bearing in (along, along + 90, along + 180, along + 270):
        found = [d for d in _near(_look(world, pose[:2], 0.35, bearing), pose[:2], 0.02) if d["category"] == "carton"]
        assert found and found[0]["pose"] == "lying", (bearing, found)


def test_a_flat_box_is_no_lying_can():
    # seed 2001's flat box (140 x 100 x 40 mm, red like the can): an axis fits its long
    # side as well as a lying can's, but it rises 4 cm above the floor, not 6.6
    flat = SimWorld(None, "house_hard", seed=2001)
    try:
        name = next(o.name for o in flat.spec.objects if o.category == "flat_box")
        xy = flat.object_poses()[name][:2]
        for distance, bearing in ((0.6, 90), (0.6, 30), (0.9, 60), (1.3, -120), (1.8, 0)):
            cans = [d for d in _near(_look(flat, xy, distance, bearing), xy) if d["category"] == "can"]
            assert not cans, (distance, bearing, cans)
    finally:
        flat.close()
