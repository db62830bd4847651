"""house_hard: the house with objects upright, lying or leaning, some on low tables, among
look-alike distractors, with printed labels, per-seed lighting, colour jitter and depth
noise (sim/varied.py, sim/appearance.py, sim/textures.py)."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

import categories
from planning import ArmKinematics
from sim import SimWorld, WorldError, load_world
from common.quiet_pybullet import pybullet as p
from sim.description import ROBOT_RADIUS
from sim.objects import CATEGORIES, DECOYS
from sim.textures import label_texture, print_mask

SEEDS = range(30)


@pytest.fixture(scope="module")
def worlds():
    return {s: load_world("house_hard", s) for s in SEEDS}


@pytest.fixture(scope="module")
def arm():
    return ArmKinematics.from_urdf()


def _category_objects(w):
    return [o for o in w.objects if o.category in categories.names()]


def test_the_world_loads_for_many_seeds_with_every_category_and_distractors(worlds):
    house = load_world("house", 0)
    for seed, w in worlds.items():
        assert [b.name for b in w.walls] == [b.name for b in house.walls]
        assert {f.name for f in house.furniture} < {f.name for f in w.furniture}
        assert w.place == house.place
        assert w.search_locations == []  # a search looks from places chosen from the map
        assert {"can", "bottle", "carton"} <= {o.category for o in w.objects}
        decoys = [o for o in w.objects if o.category in DECOYS]
        assert len(decoys) >= 4, seed
        for o in w.objects:
            assert o.pose_kind in ("upright", "lying", "tilted")
            assert o.support == "floor" or o.support in {b.name for b in w.obstacles}
            assert w.room_of(o.x, o.y) is not None, (seed, o)
        assert len({o.name for o in w.objects}) == len(w.objects)


def test_the_same_seed_gives_the_same_world():
    a, b, c = (load_world("house_hard", s) for s in (4, 4, 5))
    assert a.objects == b.objects and a.lighting == b.lighting
    assert a.objects != c.objects and a.lighting != c.lighting


def test_the_pose_kinds_mix_as_configured(worlds):
    kinds = Counter(o.pose_kind for w in worlds.values() for o in _category_objects(w))
    n = sum(kinds.values())
    mix = next(iter(worlds.values())).poses
    for kind in ("upright", "lying", "tilted"):
        want = mix.fraction(kind)
        # binomial: within 4 sigma (tilted may fall back to lying where nothing to lean on)
        assert abs(kinds[kind] / n - want) < 4 * math.sqrt(want * (1 - want) / n) + 0.02, kinds
    tables = Counter(
        o.support
        for w in worlds.values()
        for o in _category_objects(w)
        if o.pose_kind == "upright" and o.support != "floor"
    )
    assert sum(tables.values()) >= 10 and len(tables) == 3, tables  # every table is used


def test_every_object_is_within_the_arms_reach(worlds, arm):
    """On a table: its grasp height is one the level grasp reaches; lying: the grasp from
    above reaches its axis; standing or leaning: on the floor; and each has the floor
    free for the base where it grasps and backs off."""
    for seed, w in worlds.items():
        tables = {f.name: f for f in w.furniture if f.support}
        for o in _category_objects(w):
            cat = categories.get(o.category)
            plan = cat.strategy.plan_for(o.pose_kind)
            if o.pose_kind == "upright" and o.support in tables:  # on it (else leaning)
                base = tables[o.support].sz
                assert tables[o.support].distance(o.x, o.y) == 0 and base < 0.3
            else:
                base = 0.0
            if plan is None:  # a box lying on a face: held as a box standing on it
                continue
            z = base + plan.height
            assert arm.ik(plan.reach, 0.0, z, plan.pitch).ok, (seed, o, z)


def test_objects_on_tables_stand_near_an_edge_the_base_reaches(worlds):
    for seed, w in worlds.items():
        tables = {f.name: f for f in w.furniture if f.support}
        for o in w.objects:
            if o.support not in tables or o.pose_kind != "upright" or o.category not in categories.names():
                continue
            t = tables[o.support]
            c, s = math.cos(t.yaw), math.sin(t.yaw)
            u, v = c * (o.x - t.x) + s * (o.y - t.y), -s * (o.x - t.x) + c * (o.y - t.y)
            r = CATEGORIES[o.category].radius
            ok = False
            for nx, ny, inset in (
                (c, s, t.sx / 2 - u),
                (-c, -s, t.sx / 2 + u),
                (-s, c, t.sy / 2 - v),
                (s, -c, t.sy / 2 + v),
            ):
                assert inset > r, (seed, o.name)  # wholly on the table
                # an edge it stands near, with the base's spot 0.27 + 0.12 m back from it free
                bx, by = o.x + nx * 0.39, o.y + ny * 0.39
                ok |= inset <= r + 0.06 and all(ob.distance(bx, by) >= ROBOT_RADIUS for ob in w.obstacles)
            assert ok, (seed, o.name)


@pytest.mark.parametrize("seed", [1, 4, 7])
def test_objects_settle_at_rest_outside_the_furniture_and_in_their_pose(seed):
    sim = SimWorld(None, "house_hard", seed, camera=False)
    try:
        assert sim.settle_steps >= sim.spec.settle_steps > 0
        cid = sim.cid
        statics = sim.scene.statics + [sim.scene.place]
        before = sim.object_poses()
        for name, body in sim.scene.objects.items():
            lin, ang = p.getBaseVelocity(body, physicsClientId=cid)
            assert np.linalg.norm(lin) < 0.01 and np.linalg.norm(ang) < 0.1, name
            for s in statics:
                for c in p.getClosestPoints(body, s, 0.0, physicsClientId=cid):
                    assert c[8] > -0.003, (name, c[8])
        sim.advance(2.0)
        after = sim.object_poses()
        for o in sim.spec.objects:
            moved = math.dist(before[o.name][:3], after[o.name][:3])
            assert moved < 0.005, (o.name, o.pose_kind, moved)  # nothing rolls away
            if o.category not in categories.names():
                continue
            q = after[o.name][3:]
            up = abs(1 - 2 * (q[0] ** 2 + q[1] ** 2))  # |z axis . world z|
            tilt = math.degrees(math.acos(min(1.0, up)))
            want = {"upright": (0, 3), "lying": (80, 90), "tilted": (10, 60)}[o.pose_kind]
            assert want[0] <= tilt <= want[1], (o.name, o.pose_kind, tilt)
            if o.support != "floor" and o.pose_kind == "upright":
                table = next(f for f in sim.spec.furniture if f.name == o.support)
                assert after[o.name][2] == pytest.approx(table.sz + CATEGORIES[o.category].height / 2, abs=0.005)
    finally:
        sim.close()


def test_a_category_registered_at_run_time_takes_part(tmp_path):
    juice = tmp_path / "juice.py"
    juice.write_text(
        "from categories import Box, Category, Grasp, Label, register\n"
        "register(Category('juice_hard_test', Box(0.06, 0.04, 0.11), 0.05, (1, .5, 0, 1),"
        " Grasp(height=0.05), label=Label(0.02, 0.08)))\n"
    )
    categories.load(juice)
    try:
        kinds = Counter()
        for seed in range(12):
            w = load_world("house_hard", seed)
            (o,) = [o for o in w.objects if o.category == "juice_hard_test"]
            kinds[o.pose_kind] += 1
        assert len(kinds) >= 2, kinds
        sim = SimWorld(None, "house_hard", 2, camera=False)
        try:
            body = sim.scene.objects["juice_hard_test_1"]
            assert p.getVisualShapeData(body, physicsClientId=sim.cid)[0][2] == p.GEOM_MESH  # labelled
        finally:
            sim.close()
    finally:
        categories.unregister("juice_hard_test")


def test_labels_lighting_jitter_and_noise_only_where_asked():
    plain = load_world("house", 0)
    assert plain.appearance.plain and plain.lighting is None and plain.poses is None
    assert all(o.rgba is None and o.pose_kind == "upright" and o.support == "floor" for o in plain.objects)
    hard = load_world("house_hard", 0)
    a = hard.appearance
    assert a.labels and a.lighting and a.color_jitter and a.depth_noise and hard.lighting is not None
    cats = [o for o in hard.objects if o.category in categories.names()]
    assert all(o.rgba is not None and o.rgba != CATEGORIES[o.category].rgba for o in cats)


def _camera_pair(world, seed):
    sim = SimWorld(None, world, seed, camera_size=(160, 120))
    try:
        kinds = {n: p.getVisualShapeData(b, physicsClientId=sim.cid)[0][2] for n, b in sim.scene.objects.items()}
        sim.render_camera()  # the first EGL frame of a world may differ from the next
        return kinds, sim.render_camera(), sim.render_camera()
    finally:
        sim.close()


def test_rendering_labels_and_depth_noise():
    kinds, (rgb1, d1), (rgb2, d2) = _camera_pair("house", 0)
    assert kinds["can_1"] == p.GEOM_CYLINDER  # plain primitives
    assert np.array_equal(rgb1, rgb2) and np.array_equal(d1, d2, equal_nan=True)
    kinds, (rgb1, d1), (rgb2, d2) = _camera_pair("house_hard", 0)
    assert kinds["can_1"] == p.GEOM_MESH and kinds["bottle_1"] == p.GEOM_MESH  # labelled
    assert np.array_equal(rgb1, rgb2)  # noise is in the depth only
    both = np.isfinite(d1) & np.isfinite(d2)
    diff = (d1 - d2)[both]
    assert diff.std() > 0.001  # fresh noise per frame
    assert np.isnan(d1).mean() > 0.0005  # some dropouts


def test_depth_noise_grows_with_distance():
    from sim.appearance import DepthNoise, noisy_depth

    rng = np.random.default_rng(0)
    m = DepthNoise(dropout=0.0, speckle=0.0)
    for z in (0.5, 1.5, 3.0):
        d = np.full((60, 80), z, np.float32)
        got = noisy_depth(d, rng, m, fx=100.0) - z
        assert np.nanstd(got) == pytest.approx(m.a + m.b * (z - m.z0) ** 2, rel=0.1)


def test_label_textures_print_their_coverage():
    assert print_mask(200, 60, 0.3, "can").mean() == pytest.approx(0.3, abs=0.01)
    bottle = categories.get("bottle")
    img = label_texture(bottle.rgba, bottle.label, bottle.height, "bottle")
    paper = np.round(np.asarray(bottle.label.rgba[:3]) * 255)
    share = np.all(np.abs(img.astype(int) - paper) <= 1, axis=2).mean()
    band = (bottle.label.top - bottle.label.bottom) / bottle.height * 0.9
    assert share == pytest.approx(band * (1 - bottle.label.coverage), abs=0.02)


BASE = """\
name: t
bounds: [-0.5, -0.5, 4.5, 4.5]
walls: [[0, 0, 4, 0], [4, 0, 4, 4], [4, 4, 0, 4], [0, 4, 0, 0]]
rooms: {all: [0, 0, 4, 4]}
furniture:
  - {name: low, center: [2, 3], size: [1.0, 0.4, 0.22], support: true}
robot: {start: [0.6, 0.6, 0]}
"""


@pytest.mark.parametrize(
    "extra, where, message",
    [
        ("poses: {upright: 1, sideways: 2}\n", "8:21", "poses: unknown key 'sideways' (allowed: "),
        (
            "poses: {upright: 0, lying: 0, tilted: 0}\n",
            "8:8",
            "poses: the weights of upright, lying, tilted must not all be 0",
        ),
        ("poses: {tilt_deg: [40, 20]}\n", "8:19", "poses.tilt_deg must be [low, high] with low <= high"),
        ("poses: {on_tables: 2}\n", "8:20", "poses.on_tables must be a fraction in 0..1, got 2"),
        ("appearance: {labels: maybe}\n", "8:22", "appearance.labels must be true or false, got 'maybe'"),
        ("appearance: {depth_noise: {a: -1}}\n", "8:31", "appearance.depth_noise.a must be >= 0"),
        ("appearance: {lighting: {tint: x}}\n", "8:31", "appearance.lighting.tint must be a number, got 'x'"),
        ("distractors: {count: 3}\n", "8:1", "distractors: needs a 'poses' block"),
        (
            "poses: {}\ndistractors: {kinds: [teapot]}\n",
            "9:23",
            "distractors.kinds: unknown distractor 'teapot' (one of: mug,",
        ),
        (
            "poses: {}\nobjects:\n  - {category: can, pose_kind: flying}\n",
            "10:32",
            "objects[0].pose_kind: expected one of upright, lying, tilted, got 'flying'",
        ),
        (
            "poses: {}\nobjects:\n  - {category: can, support: sofa}\n",
            "10:30",
            "objects[0].support: expected 'floor' or a table (furniture with 'support: true': low), got 'sofa'",
        ),
        (
            "poses: {}\nobjects:\n  - {category: can, support: low, pose_kind: lying}\n",
            "10:30",
            "objects[0]: objects on a table stand upright",
        ),
        ("objects:\n  - {category: can, pose_kind: lying}\n", "9:21", "objects[0].pose_kind: needs a 'poses' block"),
    ],
)
def test_mistakes_in_the_new_keys_name_file_line_and_column(tmp_path, extra, where, message):
    f = tmp_path / "t.yaml"
    f.write_text(BASE + extra)
    with pytest.raises(WorldError) as e:
        load_world(f)
    assert str(e.value).startswith(f"{f}:{where}: {message}"), str(e.value)


def test_explicit_pose_kinds_and_supports(tmp_path):
    f = tmp_path / "t.yaml"
    f.write_text(
        BASE + "poses: {}\nobjects:\n  - {category: can, support: low}\n"
        "  - {category: bottle, pose_kind: tilted}\n  - {category: carton, pose_kind: lying}\n"
    )
    for seed in range(5):
        can, bottle, carton = load_world(f, seed).objects
        assert (can.pose_kind, can.support) == ("upright", "low") and can.z > 0.22
        assert bottle.pose_kind == "tilted" and bottle.support.startswith("wall_")
        assert carton.pose_kind == "lying" and carton.quat is not None


def test_a_box_on_a_table_shows_a_side_its_grasp_takes_it_from_to_the_free_edge(worlds):
    boxes = 0
    for seed, w in worlds.items():
        tables = {f.name: f for f in w.furniture if f.support}
        for o in _category_objects(w):
            plan = categories.get(o.category).strategy.plan_for("upright")
            if o.support not in tables or o.pose_kind != "upright" or not plan.sides:
                continue
            boxes += 1
            # the base comes across the free edge, facing the table (see the test above)
            t = tables[o.support]
            heading = min(
                (
                    math.atan2(-ny, -nx)
                    for nx, ny in ((1, 0), (-1, 0), (0, 1), (0, -1))
                    if t.distance(o.x + nx * 0.39, o.y + ny * 0.39) > 0.1
                    and all(ob.distance(o.x + nx * 0.39, o.y + ny * 0.39) >= ROBOT_RADIUS for ob in w.obstacles)
                ),
                key=lambda h: 0.0,
                default=None,
            )
            assert heading is not None, (seed, o.name)
            assert plan.off_sides(heading, o.yaw) <= 0.5 * plan.tolerance + 1e-6, (seed, o.name)
    assert boxes >= 1
