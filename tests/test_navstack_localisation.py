"""navstack's localiser core (map_io, likelihood field, particle filter, Amcl) on the
synthetic house: tests/fixtures/house.{pgm,yaml} is `actorbt sim map --world house`,
tests/fixtures/house_world.yaml the world it was made from (the ray caster's geometry)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navstack.amcl import LOCALISED, UNINITIALISED, Amcl, AmclParams, Scan, compose, inverse
from navstack.likelihood_field import LaserModelParams, LikelihoodField
from navstack.map_io import MapError, OccupancyMap, read_map_yaml, write_map_yaml
from navstack.particle_filter import FilterParams, ParticleFilter
from navstack.synthetic import Boxes, LaserSpec, SyntheticWorld, world_boxes

FIXTURES = Path(__file__).parent / "fixtures"


@pytest.fixture(scope="module")
def house():
    return read_map_yaml(FIXTURES / "house.yaml")


@pytest.fixture(scope="module")
def boxes():
    return world_boxes(FIXTURES / "house_world.yaml")


def make(house, boxes, seed=0, **kw):
    world = SyntheticWorld(house, boxes, seed=seed, unmapped=kw.pop("unmapped", 8))
    amcl = Amcl(house, AmclParams(laser_pose=LaserSpec().pose, **kw), seed=seed, clock=lambda: world.t)
    return world, amcl


def drive(world, amcl, seconds, on_pose=None):
    """Run the world for ``seconds``, feeding the localiser; on_pose(sample, pose) at 10 Hz."""
    end = world.t + seconds
    k = 0
    while world.t < end - 1e-9:
        s = world.step()
        amcl.on_odometry(s.odom)
        if s.scan is not None:
            amcl.on_scan(s.scan, s.odom)
        k += 1
        if on_pose and k % 2 == 0:
            on_pose(s, amcl.pose(s.odom))


def error(pose, truth):
    return math.hypot(pose[0] - truth[0], pose[1] - truth[1]), abs(math.remainder(pose[2] - truth[2], 2 * math.pi))


# -- map_io ---------------------------------------------------------------------------------
def test_map_io_reads_the_sim_map(house):
    assert house.data.shape == (180, 220)
    assert house.resolution == 0.05 and house.origin == (-0.5, -0.5, 0.0)
    assert house.value_at(1.0, 1.0) == 0  # the living room
    assert house.value_at(0.0, 1.0) == 100  # the west wall
    assert house.value_at(-0.4, 1.0) == -1  # outside the house
    assert house.value_at(9.65, 2.5) == 100  # the kitchen counter
    assert set(np.unique(house.data)) == {-1, 0, 100}


def test_map_io_round_trip_and_modes(tmp_path, house):
    rotated = OccupancyMap(house.data, house.resolution, (1.0, 2.0, 0.3))
    y, _ = write_map_yaml(rotated, tmp_path / "m.yaml")
    back = read_map_yaml(y)
    assert np.array_equal(back.data, house.data) and back.origin == pytest.approx((1.0, 2.0, 0.3))
    # a rotated origin moves the cells: cell (row 0, col 1)'s centre
    x, yy = back.to_world(1.5, 0.5)
    assert (x, yy) == pytest.approx(
        (
            1.0 + 1.5 * 0.05 * math.cos(0.3) - 0.5 * 0.05 * math.sin(0.3),
            2.0 + 1.5 * 0.05 * math.sin(0.3) + 0.5 * 0.05 * math.cos(0.3),
        )
    )
    # an ASCII PGM, top row first: scale mode, negate
    (tmp_path / "a.pgm").write_text("P2\n# c\n3 2\n255\n0 128 255\n254 205 10\n")
    (tmp_path / "a.yaml").write_text(
        "image: a.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: scale\n"
    )
    a = read_map_yaml(tmp_path / "a.yaml")
    assert a.data[1].tolist() == [100, 66, 0]  # the image's top row is the map's last
    assert a.data[0].tolist() == [0, 0, 100]  # 205 is p = 0.196, just above free: 0
    (tmp_path / "b.yaml").write_text("image: a.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 1\n")
    b = read_map_yaml(tmp_path / "b.yaml")
    assert b.data[1].tolist() == [0, -1, 100]
    (tmp_path / "c.yaml").write_text("image: a.pgm\nresolution: 0.1\n")
    with pytest.raises(MapError, match="origin"):
        read_map_yaml(tmp_path / "c.yaml")


def test_map_from_and_to_an_occupancy_grid_message(house):
    msg = OccupancyMap(house.data, 0.05, (-0.5, -0.5, 0.2)).to_msg()
    back = OccupancyMap.from_msg(msg)
    assert np.array_equal(back.data, house.data) and back.origin == pytest.approx((-0.5, -0.5, 0.2))


# -- the likelihood field -------------------------------------------------------------------------
def test_likelihood_field_distances_are_to_the_wall_surface(house):
    lf = LikelihoodField(house, LaserModelParams(max_dist=2.0))
    # the west wall's inner face is x = 0.05; 1 cm sub-cells
    d = lf.distance_at(np.array([0.055, 0.30, 1.05, -5.0, 0.03]), np.array([2.0, 2.0, 2.0, 2.0, 2.0]))
    assert d[0] == pytest.approx(0.005, abs=0.006)
    assert d[1] == pytest.approx(0.25, abs=0.011)
    assert d[2] == pytest.approx(1.0, abs=0.011)
    assert d[3] == 2.0  # off the map: max_dist
    assert d[4] == pytest.approx(0.02, abs=0.011)  # inside the wall: out to its face
    amcl_like = LikelihoodField(house, LaserModelParams(surface=False, upsample=1))
    # AMCL: cell centre (0.325) to the wall cell centre (0.025)
    assert amcl_like.distance_at(np.array([0.32]), np.array([2.0]))[0] == pytest.approx(0.30)


def test_scoring_is_vectorised_over_particles_and_beams(house, boxes):
    world = SyntheticWorld(house, boxes, seed=1, unmapped=0)
    scan = world.step().scan
    amcl = Amcl(house, AmclParams(laser_pose=LaserSpec().pose), seed=0)
    xy = amcl.beams(scan, 40)
    truth = np.array(world.truth)
    poses = np.array([truth, truth + [0.2, 0, 0], truth + [0, 0, 0.2], truth + [1, 1, 1]])
    lf = amcl.pf.field
    logw, match = lf.log_weights(poses, xy, scan.range_max)
    for i, p in enumerate(poses):  # one pose at a time, by hand
        c, s = math.cos(p[2]), math.sin(p[2])
        ex, ey = p[0] + c * xy[:, 0] - s * xy[:, 1], p[1] + s * xy[:, 0] + c * xy[:, 1]
        d = lf.distance_at(ex, ey)
        pz = 0.5 * np.exp(-(d**2) / (2 * 0.1**2)) + 0.5 / scan.range_max
        assert logw[i] == pytest.approx(np.log(pz).sum(), rel=1e-4)
    assert np.argmax(logw) == 0


# -- the filter --------------------------------------------------------------------------------------
def test_motion_model_without_noise_follows_the_odometry(house):
    pf = ParticleFilter(house, FilterParams(alpha1=0, alpha2=0, alpha3=0, alpha4=0), seed=0)
    pf.initialise((2.0, 2.0, 0.5), np.diag([0.04, 0.04, 0.1]), n=50)
    before = pf.particles.copy()
    old, new = (1.0, 1.0, 0.2), (1.3, 0.8, -0.4)  # forward, sideways and a turn; then backwards
    pf.predict(old, new)
    pf.predict(new, compose(new, (-0.2, 0.0, 0.0)))
    step = compose(inverse(old), compose(new, (-0.2, 0.0, 0.0)))
    for b, a in zip(before, pf.particles):
        assert a == pytest.approx(compose(tuple(b), step), abs=1e-9)


def test_kld_and_clusters(house):
    pf = ParticleFilter(house, seed=0)
    pf.global_localisation()
    assert len(pf.particles) == 2000
    pf.resample()
    assert len(pf.particles) == 2000  # spread over the house: the maximum
    pf.initialise((2.0, 2.0, math.pi - 0.01), np.diag([0.01**2, 0.01**2, 0.02**2]))
    pf.resample()
    assert len(pf.particles) <= 501  # converged: the minimum (AMCL stops one past it)
    est = pf.estimate()  # the heading wraps round: one cluster
    assert est.clusters == 1 and abs(math.remainder(est.pose[2] - math.pi, 2 * math.pi)) < 0.01
    # two blobs, the heavier one wins
    a = pf.rng.normal((2.0, 2.0, 0.0), 0.02, size=(300, 3))
    b = pf.rng.normal((6.0, 3.0, 1.0), 0.02, size=(200, 3))
    pf.particles, pf.weights = np.vstack([a, b]), np.r_[np.full(300, 0.4 / 300), np.full(200, 0.6 / 200)]
    est = pf.estimate()
    assert est.clusters == 2 and est.pose == pytest.approx((6.0, 3.0, 1.0), abs=0.01)
    assert est.weight == pytest.approx(0.6)


# -- the localiser on the synthetic house -------------------------------------------------------------
def test_converges_and_tracks_from_an_initial_pose(house, boxes):
    world, amcl = make(house, boxes, seed=2)
    assert amcl.status.state == UNINITIALISED
    x, y, th = world.truth
    amcl.on_odometry(world.odom)
    amcl.initialise((x + 0.15, y - 0.1, th + 0.1), np.diag([0.2**2, 0.2**2, 0.15**2]))
    errs = []
    drive(world, amcl, 40, lambda s, p: errs.append(error(p, s.truth)) if world.distance > 1 else None)
    pos = np.array([e[0] for e in errs])
    yaw = np.array([e[1] for e in errs])
    assert world.distance > 6
    assert math.sqrt(np.mean(pos**2)) < 0.05 and pos.max() < 0.10
    assert math.degrees(math.sqrt(np.mean(yaw**2))) < 2.0
    assert amcl.status.state == LOCALISED and amcl.status.recoveries == 0
    assert np.median(amcl.update_times) < 0.020
    assert amcl.status.particles < 1000  # KLD shrank the set


def test_global_localisation_finds_the_robot(house, boxes):
    world, amcl = make(house, boxes, seed=5)
    drive(world, amcl, 3)  # somewhere on the tour, nothing told
    amcl.global_localisation()  # from the next scan
    assert amcl.status.state != LOCALISED
    drive(world, amcl, 5)
    e, ey = error(amcl.pose(), world.truth)
    assert e < 0.10 and ey < math.radians(5)
    assert amcl.status.state == LOCALISED


def test_uniform_global_localisation_in_a_distinctive_room(house, boxes):
    """AMCL's own global localisation (uniform particles, no scan-informed seeding, no
    recovery) in the bedroom alone: it converges, though not always (one seed in eight
    locks onto a wrong pose), hence 3 of 4."""
    bedroom = OccupancyMap(house.data[100:, :91], 0.05, (-0.5, 4.5, 0.0))  # x -0.5 .. 4.05, y 4.5 .. 8.5
    tour = [(0.8, 5.3), (3.3, 5.3), (3.3, 6.7), (2.6, 6.6)]
    found = 0
    for seed in range(4):
        world = SyntheticWorld(bedroom, boxes, tour, seed=seed, unmapped=2)
        amcl = Amcl(
            bedroom,
            AmclParams(laser_pose=LaserSpec().pose, auto_recover=False),
            FilterParams(max_particles=5000),
            seed=seed,
            clock=lambda: world.t,
        )
        amcl.global_localisation(informed=False)
        assert len(amcl.pf.particles) == 5000
        drive(world, amcl, 20)
        e, ey = error(amcl.pose(), world.truth)
        found += e < 0.10 and ey < math.radians(5)
    assert found >= 3


def rectangular_room(width: float = 4.0, depth: float = 3.0, res: float = 0.05):
    """An empty walled room centred on the origin (its map and its boxes): every pose in it
    looks like the pose turned half round about the centre."""
    t = 0.1
    boxes = Boxes.from_list(
        [
            (0, -depth / 2, width + t, t, 0),
            (0, depth / 2, width + t, t, 0),
            (-width / 2, 0, t, depth + t, 0),
            (width / 2, 0, t, depth + t, 0),
        ]
    )
    ox, oy = -width / 2 - 0.5, -depth / 2 - 0.5
    xs = ox + (np.arange(int(round((width + 1) / res))) + 0.5) * res
    ys = oy + (np.arange(int(round((depth + 1) / res))) + 0.5) * res
    x, y = np.meshgrid(xs, ys)
    data = np.where((np.abs(x) < width / 2) & (np.abs(y) < depth / 2), 0, -1).astype(np.int8)
    data[boxes.contains(x.ravel(), y.ravel()).reshape(x.shape)] = 100
    return OccupancyMap(data, res, (ox, oy, 0.0)), boxes


def test_a_global_localisation_in_a_symmetric_room_stays_uncertain():
    """The robot stands still off the centre of an empty rectangular room: the scan fits
    its pose and the pose turned half round about the centre equally. The filter's
    weights would pick one (the twin seeded nearer its optimum wins the first update:
    'localised', std 1 cm, half the time 2-3 m off); the uniqueness check keeps it
    uncertain and says why."""
    room, walls = rectangular_room()
    for seed, pose in enumerate([(1.1, 0.6, 0.4), (-0.7, -0.9, 2.5), (0.4, 0.2, -1.2)]):
        world = SyntheticWorld(room, walls, [(0.0, 0.0), (1.0, 0.0)], seed=seed, unmapped=0, speed=0.0, turn=0.0)
        world.teleport(pose)
        amcl = Amcl(room, AmclParams(laser_pose=LaserSpec().pose), seed=seed, clock=lambda: world.t)
        amcl.global_localisation()
        states = set()
        while world.t < 6.0:
            s = world.step()
            amcl.on_odometry(s.odom)
            if s.scan is not None:
                amcl.request_nomotion_update()  # as the localiser does while it waits
                amcl.on_scan(s.scan, s.odom)
                states.add(amcl.status.state)
        assert LOCALISED not in states
        st = amcl.status
        assert st.ambiguous and st.rival_score > st.score - 0.1 and st.updates > 20
        assert st.std_xy < 0.12  # the filter alone would have said localised


def test_a_kidnapping_is_noticed_and_recovered(house, boxes):
    world, amcl = make(house, boxes, seed=7)
    amcl.initialise(world.truth, np.diag([0.05**2, 0.05**2, 0.05**2]), odom=world.odom)
    drive(world, amcl, 15)
    assert amcl.status.state == LOCALISED and amcl.status.last_lost is None
    pose, target = world.kidnap_pose()
    world.teleport(pose, target)
    t0 = world.t
    drive(world, amcl, 5)
    assert amcl.status.last_lost is not None and amcl.status.last_lost - t0 <= 5.0
    drive(world, amcl, 10)
    e, _ = error(amcl.pose(), world.truth)
    assert e < 0.10 and amcl.status.state == LOCALISED


def test_no_false_alarm_when_an_unmapped_box_appears(house, boxes):
    """A box dropped in front of the robot hides part of the scan: not a kidnapping."""
    world, amcl = make(house, boxes, seed=4, unmapped=0)
    amcl.initialise(world.truth, np.diag([0.05**2, 0.05**2, 0.05**2]), odom=world.odom)
    drive(world, amcl, 8)
    from navstack.synthetic import Boxes

    x, y, th = world.truth
    world.boxes = world.boxes + Boxes.from_list(
        [(x + 0.5 * math.cos(th + 0.8), y + 0.5 * math.sin(th + 0.8), 0.3, 0.3, 0.0)]
    )
    drive(world, amcl, 6)
    assert error(amcl.pose(), world.truth)[0] < 0.10


def test_a_false_alarm_at_a_standstill_does_not_move_the_published_pose(house, boxes):
    """The robot stands at a table with things all round its laser (an object, the arm):
    no scan fits the map, lost is declared and the filter relocalises. The published pose
    holds the last localised one meanwhile (a half-done relocalisation may sit on a
    look-alike place metres away); once the view clears and the robot drives on, the
    filter converges and is adopted again."""
    from navstack.synthetic import Boxes

    world, amcl = make(house, boxes, seed=4, unmapped=0)
    amcl.initialise(world.truth, np.diag([0.05**2, 0.05**2, 0.05**2]), odom=world.odom)
    drive(world, amcl, 8)
    assert amcl.status.state == LOCALISED
    speed, turn, clear_view = world.speed, world.turn, world.boxes
    world.speed = world.turn = 0.0  # standing still
    lx, ly, _ = compose(world.truth, LaserSpec().pose)
    ring = [(lx + 0.3 * math.cos(a), ly + 0.3 * math.sin(a), 0.12, 0.12, a) for a in np.arange(0, 2 * math.pi, 0.35)]
    world.boxes = clear_view + Boxes.from_list(ring)
    published = []
    drive(world, amcl, 8, lambda s, p: published.append(error(p, s.truth)[0]))
    assert amcl.status.lost_count >= 1 and amcl.holding
    assert max(published) < 0.05
    world.boxes, world.speed, world.turn = clear_view, speed, turn
    drive(world, amcl, 12, lambda s, p: published.append(error(p, s.truth)[0]))
    assert amcl.status.state == LOCALISED and not amcl.holding
    assert max(published) < 0.10


def _converged_after_lost(world, amcl, held, found):
    """The state in which a relocalisation after a lost converges: the published pose
    held at ``held``, the filter's at ``found``; returns the newest scan's sample."""
    s = world.step()
    while s.scan is None:
        s = world.step()
    amcl.holding = True
    amcl.map_to_odom = compose(held, inverse(s.odom))
    amcl.filter_map_to_odom = compose(found, inverse(s.odom))
    amcl._adopt_or_keep(s.scan, s.odom)
    return s


def test_a_relocalisation_elsewhere_that_fits_no_better_is_not_adopted(house, boxes):
    """By an unmapped object the right pose fits the scan less: lost is declared, and
    the search may settle on a look-alike place metres away. The held pose is kept and
    the filter starts again round it."""
    from navstack.synthetic import Boxes

    world, amcl = make(house, boxes, seed=4, unmapped=0)
    amcl.initialise(world.truth, np.diag([0.05**2, 0.05**2, 0.05**2]), odom=world.odom)
    drive(world, amcl, 4)
    world.speed = world.turn = 0.0
    x, y, th = world.truth
    world.boxes = world.boxes + Boxes.from_list([(x + 0.45 * math.cos(th), y + 0.45 * math.sin(th), 0.3, 0.5, th)])
    s = _converged_after_lost(world, amcl, world.truth, compose(world.truth, (0.0, 3.0, 1.5)))
    assert not amcl.holding and amcl.status.kept_count == 1
    assert error(amcl.pose(s.odom), s.truth)[0] < 0.01
    assert np.all(np.abs(amcl.pf.particles[:, :2].mean(axis=0) - s.truth[:2]) < 0.05)
    assert amcl.status.baseline == amcl.status.score < 0.9  # the present, lowered fit
    drive(world, amcl, 3)
    assert amcl.status.state == LOCALISED and error(amcl.pose(), world.truth)[0] < 0.05


def test_a_relocalisation_that_fits_better_is_adopted_however_far(house, boxes):
    """A kidnapping: the held pose is the wrong one, and the scan fits the found pose."""
    world, amcl = make(house, boxes, seed=4, unmapped=0)
    amcl.initialise(world.truth, np.diag([0.05**2, 0.05**2, 0.05**2]), odom=world.odom)
    drive(world, amcl, 4)
    world.speed = world.turn = 0.0
    wrong = compose(world.truth, (-2.0, 1.0, 2.0))
    s = _converged_after_lost(world, amcl, wrong, world.truth)
    assert amcl.status.kept_count == 0
    assert error(amcl.pose(s.odom), s.truth)[0] < 1e-6


def test_reproducible_with_a_seed(house, boxes):
    def run(seed):
        world, amcl = make(house, boxes, seed=1)
        amcl.pf.rng = amcl.rng = np.random.default_rng(seed)
        amcl.initialise(world.truth, np.diag([0.1, 0.1, 0.05]), odom=world.odom)
        drive(world, amcl, 6)
        return amcl.pf.particles.copy(), amcl.pose()

    (p1, e1), (p2, e2), (p3, _) = run(11), run(11), run(12)
    assert np.array_equal(p1, p2) and e1 == e2
    assert not (p1.shape == p3.shape and np.array_equal(p1, p3))


def test_scan_from_a_laser_scan_message():
    from sensor_msgs.msg import LaserScan

    msg = LaserScan(
        angle_min=-math.pi,
        angle_increment=math.pi / 2,
        range_min=0.12,
        range_max=3.5,
        ranges=[1.0, float("inf"), 0.05, 3.5],
    )
    scan = Scan.from_msg(msg)
    assert scan.valid().tolist() == [True, False, False, False]
    assert scan.angles == pytest.approx([-math.pi, -math.pi / 2, 0, math.pi / 2])
