"""Perception of objects lying on their side, and of labelled ones, in house_hard's look
(printed labels, light, colour jitter, depth noise): detect() on rendered frames."""

import dataclasses
import math

import numpy as np
import pytest

from actors.perception import _score, _segments, backproject, detect, registered_appearances
from bench.bench_perception_hard import _frame, _teleport
from sim import SimWorld
from common.quiet_pybullet import pybullet as p

SPOT = (1.6, 1.6)  # open floor in the living room


@pytest.fixture(scope="module")
def sim():
    s = SimWorld(None, "house_hard", seed=0)
    yield s
    s.close()


def _put(sim, name, quat, z):
    body = sim.scene.objects[name]
    p.resetBasePositionAndOrientation(body, [SPOT[0], SPOT[1], z], quat, physicsClientId=sim.cid)
    for _ in range(120):
        p.stepSimulation(physicsClientId=sim.cid)


def _look(sim, bearing, distance=0.6):
    _teleport(sim, SPOT[0] - distance * math.cos(bearing), SPOT[1] - distance * math.sin(bearing), bearing)
    return detect(_frame(sim), registered_appearances())


def _near(dets, category, xy, tol=0.03):
    return [d for d in dets if d["category"] == category and math.dist((d["x"], d["y"]), xy) < tol]


@pytest.mark.parametrize("category,radius", [("can", 0.033), ("bottle", 0.035)])
def test_a_lying_body_is_recognised_with_its_axis(sim, category, radius):
    name = next(n for n in sim.object_names() if sim.object_category(n) == category)
    axis_yaw = 0.7
    _put(sim, name, p.getQuaternionFromEuler([math.pi / 2, 0.0, axis_yaw - math.pi / 2]), radius + 0.002)
    app = registered_appearances()[category]
    pose = sim.object_pose(name)  # the frame (a body's base pose is its centre of mass)
    pos, orn = pose[:3], pose[3:]
    R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
    body_centre = np.array(pos) + R @ [0, 0, 0.5 * app.body_top - 0.5 * app.height]
    true_yaw = math.atan2(R[1, 2], R[0, 2])
    seen = 0
    # from the side and obliquely (seen nearly end-on, the body hides behind the neck
    # or a cap, and it is often missed: see docs/perception.md)
    for bearing in (0.0, 2.4, -0.9, 2.2):
        found = _near(_look(sim, bearing), category, body_centre[:2])
        if not found:
            continue
        seen += 1
        d = found[0]
        assert d["pose"] == "lying", d
        assert math.dist((d["x"], d["y"]), body_centre[:2]) < 0.01, d
        err = abs(math.remainder(d["yaw"] - true_yaw, math.pi))
        assert math.degrees(err) < 5.0, (d["yaw"], true_yaw)
    assert seen >= 3
    sim.set_object_pose(name, 40.0, 40.0)


def test_a_labelled_bottle_standing_is_one_bottle(sim):
    # the cream label splits the green in two: both parts are one bottle
    name = next(n for n in sim.object_names() if sim.object_category(n) == "bottle")
    _put(sim, name, p.getQuaternionFromEuler([0, 0, 0.3]), 0.1526)
    for bearing in (0.5, -1.0):
        dets = _look(sim, bearing, 0.7)
        found = _near(dets, "bottle", SPOT, 0.01)
        assert found and found[0]["pose"] == "upright", dets
        assert abs(found[0]["z"]) < 0.01, found[0]  # its base, not the label's top
    sim.set_object_pose(name, 40.0, 40.0)


def test_a_labelled_bottle_on_a_table_seen_across_it_has_its_base_on_the_table():
    """From the low camera (9 cm), across the study table, the table's edge hides the
    green below the bottle's label: the green in view ends at the label's top, 0.15 m
    above the base, and the label goes on below it."""
    world = SimWorld(None, "house_hard", seed=2011)  # a bottle at the table's far end
    try:
        bottle = next(
            n for n in world.object_names() if world.object_category(n) == "bottle" and world.object_pose(n)[2] > 0.2
        )
        x, y, z = world.object_pose(bottle)[:3]
        base = z - 0.305 / 2  # its frame is at half its height
        _teleport(world, 6.4, 6.6, math.atan2(y - 6.6, x - 6.4))
        standing = []
        for _ in range(3):  # (seen so, part of it, its lean is noise: some frames say lying)
            dets = detect(_frame(world), registered_appearances())
            found = _near(dets, "bottle", (x, y), 0.08)  # (from 1.7 m, a few cm off)
            assert found, dets
            standing += [d for d in found if d["pose"] != "lying"]
        assert standing
        for d in standing:
            assert abs(d["z"] - base) < 0.03 and d["height"] > 0.15, (d["z"], base)
    finally:
        world.close()


@pytest.mark.parametrize("roll_axis,height,across", [("x", 0.045, 0.070), ("y", 0.070, 0.045)])
def test_a_lying_carton_is_recognised_with_the_face_it_lies_on(sim, roll_axis, height, across):
    # 70 x 45 x 120 mm: lying on its 70 mm face it is 45 mm high, and the other way round
    name = next(n for n in sim.object_names() if sim.object_category(n) == "carton")
    axis_yaw = 0.4  # where its long (z) side points
    euler = [math.pi / 2, 0.0, axis_yaw + math.pi / 2] if roll_axis == "x" else [0.0, math.pi / 2, axis_yaw]
    _put(sim, name, p.getQuaternionFromEuler(euler), height / 2 + 0.002)
    pose = sim.object_pose(name)
    R = np.array(p.getMatrixFromQuaternion(pose[3:])).reshape(3, 3)
    assert abs(R[2, 2]) < 0.05  # its long side is level
    true_yaw = math.atan2(R[1, 2], R[0, 2])
    seen = 0
    for bearing in (0.0, 1.2, -1.4):
        found = _near(_look(sim, bearing, 0.7), "carton", pose[:2], 0.02)
        if not found:
            continue
        seen += 1
        d = found[0]
        assert d["pose"] == "lying" and d["width"] == pytest.approx(across), d
        assert math.degrees(abs(math.remainder(d["yaw"] - true_yaw, math.pi))) < 6.0, (d["yaw"], true_yaw)
    assert seen >= 2
    sim.set_object_pose(name, 40.0, 40.0)


def test_a_patch_of_a_table_in_a_categorys_colour_is_no_object():
    # under seed 2003's light, the coffee table (3.0-4.0 x 2.35-2.85 m) breaks into
    # patches of two hues, one of them the carton's; strips of it have a carton's size
    world = SimWorld(None, "house_hard", seed=2003)
    try:
        for yaw in (-20, -10, 0, 10):
            _teleport(world, 1.75, 1.95, 0.35 + math.radians(yaw))
            dets = detect(_frame(world), registered_appearances())
            near_table = [d for d in dets if d["category"] != "unknown" and 2.9 < d["x"] < 4.1 and 2.25 < d["y"] < 2.95]
            assert not near_table, near_table
    finally:
        world.close()


#: seed 2004's pallet (0.6 x 0.4 x 0.12 m: a carton's height; under that light in the
#: carton's hue) seen so that a carton-sized part of it shows: the robot's pose, and where
#: a carton is put in the same frame (None: none)
PALLET_VIEWS = [
    ((8.57, 3.56, 2.785), (7.41, 3.89)),  # the search's view from 3 m: its corner at
    #                                             the image's right border, the rest out of view
    ((6.72, 5.50, 2.033), (6.43, 5.97)),  # the close look from 0.5 m: the same
    ((7.89, 2.80, math.pi / 2), (7.79, 3.80)),  # its corner beside a nearer wall, its 0.4 m
    #                                             side seen edge-on
    ((4.59, 7.79, -0.349), None),  # its corner beside the nearer desk, of its hue
]


def test_a_part_of_the_pallet_is_no_carton_and_a_carton_in_the_same_view_is():
    # the pick-and-place mission went for a "carton" at the pallet's corner, seen from 3 m
    # and from the close look: a part of a long box must not pass for a carton's face
    world = SimWorld(None, "house_hard", seed=2004)
    try:
        pallet = world.spec.place
        carton = next(n for n in world.object_names() if world.object_category(n) == "carton")
        for (x, y, yaw), put in PALLET_VIEWS:
            world.set_object_pose(carton, *(put or (40.0, 40.0)), 0.3)
            _teleport(world, x, y, yaw)
            dets = detect(_frame(world), registered_appearances())
            on_pallet = [
                d
                for d in dets
                if d["category"] != "unknown"
                and abs(d["x"] - pallet.x) < pallet.sx / 2 + 0.1
                and abs(d["y"] - pallet.y) < pallet.sy / 2 + 0.1
            ]
            assert not on_pallet, ((x, y, yaw), on_pallet)
            if put:
                assert _near(dets, "carton", put, 0.02), ((x, y, yaw), dets)
    finally:
        world.close()


def test_a_segment_of_a_categorys_hue_and_shape_but_dull_is_not_of_that_category(sim):
    # brown furniture whose hue drifts into a category's keeps about 0.45 of its saturation
    name = next(n for n in sim.object_names() if sim.object_category(n) == "can")
    _put(sim, name, p.getQuaternionFromEuler([0, 0, 0]), 0.062)
    _look(sim, 0.4, 0.7)
    frame = _frame(sim)
    app = registered_appearances()["can"]
    segs = [s for s in _segments(frame, backproject(frame), [app]) if s.colour == app.colour]
    seg = max(segs, key=lambda s: len(s.pts))
    assert seg.saturation > 0.8 * app.saturation
    assert _score(seg, app)[0] > 0.5
    dull = dataclasses.replace(seg, saturation=0.45 * app.saturation)
    assert _score(dull, app) == (0.0, {"reason": "colour too dull"})
    sim.set_object_pose(name, 40.0, 40.0)


def test_a_leaning_carton_is_recognised_tilted_with_its_lean():
    # seed 2001's carton leans 38 degrees against the north wall (towards +y); seen from
    # ~0.8 m it is a tilted carton at its centre, leaning that way, its base below its top
    world = SimWorld(None, "house_hard", seed=2001)
    try:
        name = next(n for n in world.object_names() if world.object_category(n) == "carton")
        pose = world.object_poses()[name]
        R = np.array(p.getMatrixFromQuaternion(pose[3:])).reshape(3, 3)
        up = R[:, 2] if R[2, 2] > 0 else -R[:, 2]
        tilt = math.degrees(math.acos(up[2]))
        assert 30 < tilt < 40
        lean = math.atan2(up[1], up[0])
        for bearing in (0.0, math.pi / 2, math.pi):
            _teleport(world, pose[0] - 0.8 * math.cos(bearing), pose[1] - 0.8 * math.sin(bearing), bearing)
            dets = detect(_frame(world), registered_appearances())
            found = _near(dets, "carton", pose[:2], 0.03)
            assert found, (bearing, dets)
            d = found[0]
            assert d["pose"] == "tilted", d
            assert math.degrees(abs(math.remainder(d["yaw"] - lean, 2 * math.pi))) < 20.0, (d["yaw"], lean)
            assert abs(d["tilt_deg"] - tilt) < 10.0, d
            base, axis = np.array(d["axis_base"]), np.array(d["axis_dir"])
            assert axis[2] > 0 and float(axis @ up) > math.cos(math.radians(15)), d
            assert np.linalg.norm(base - (np.array(pose[:3]) - 0.06 * up)) < 0.03, d
    finally:
        world.close()


def test_a_carton_leaning_on_brown_furniture_is_its_own_segment():
    # seed 2008's carton leans 29 degrees on the wardrobe, whose brown has a hue near the
    # carton's yellow but half its saturation: taken for yellow, the wardrobe and the
    # carton were one segment, too dull and too large to be anything
    world = SimWorld(None, "house_hard", seed=2008)
    try:
        name = next(n for n in world.object_names() if world.object_category(n) == "carton")
        assert next(o for o in world.spec.objects if o.name == name).support == "wardrobe"
        pose = world.object_poses()[name]
        for distance, bearing in ((0.9, 90), (0.9, 120), (1.3, 90), (1.8, 90)):
            a = math.radians(bearing)
            _teleport(world, pose[0] - distance * math.cos(a), pose[1] - distance * math.sin(a), a)
            found = _near(detect(_frame(world), registered_appearances()), "carton", pose[:2], 0.03)
            assert found and found[0]["pose"] == "tilted", (distance, bearing, found)
    finally:
        world.close()


@pytest.fixture
def cone():
    """A tapered cup (50 mm at the foot, 72 at the rim, 95 mm tall, as in
    docs/categories.md), registered while the test runs."""
    import categories
    from categories import Category, Grasp, Revolution

    cat = categories.register(
        Category(
            name="cone_test",
            shape=Revolution(((0.019, 0.0259), (0.038, 0.0282), (0.057, 0.0305), (0.076, 0.0328), (0.095, 0.0351))),
            mass=0.012,
            rgba=(0.10, 0.30, 0.90, 1.0),
            grasp=Grasp(height=0.050, open_width=0.085, lift=0.10),
        )
    )
    try:
        yield cat
    finally:
        categories.unregister("cone_test")


def test_a_lying_tapered_body_is_recognised_from_its_side(cone):
    """A cone fits no cylinder of its foot's radius: its axis is fitted to its whole
    profile. (Fitted as a cylinder, 3 of these 8 views recognised it.)"""
    s = SimWorld(None, "house_hard", seed=0)
    try:
        name = next(n for n in s.object_names() if s.object_category(n) == "cone_test")
        axis_yaw = 0.7
        _put(s, name, p.getQuaternionFromEuler([math.pi / 2, 0.0, axis_yaw - math.pi / 2]), 0.04)
        pose = s.object_pose(name)
        seen = []
        for bearing in (0.0, 2.4, -0.9, 2.2):  # from the side and obliquely
            for distance in (0.6, 1.0):
                found = _near(_look(s, bearing, distance), "cone_test", pose[:2], tol=0.06)
                seen += [(bearing, distance)] if found else []
                for d in found:
                    assert d["pose"] == "lying", d
                    assert abs(math.remainder(d["yaw"] - axis_yaw, math.pi)) < math.radians(10), d
        assert len(seen) >= 7, seen
    finally:
        s.close()
