"""navstack.slam on the synthetic house: one loop with wrong odometry and a noisy LDS-01.

The thresholds are set between what Slam reaches (bench/bench_slam.py) and what the
odometry alone gives: a front end or a loop closure that stops working fails them.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navstack.map_io import read_map_yaml
from navstack.pose_graph import compose, relative
from navstack.slam import Slam, SlamParams
from navstack.synthetic import SyntheticWorld, world_boxes

FIXTURES = Path(__file__).parent / "fixtures"


def drive_the_house(**params):
    """One loop of the synthetic house with a Slam of ``params``: (world, slam, samples)."""
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=0, start=0, reverse=False)
    slam = Slam(SlamParams(initial_pose=world.truth, **params))
    samples = []
    while world.target < len(world.tour) + 2 and world.t < 400:
        s = world.step()
        if s.scan is not None:
            slam.add(s.odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min)
            samples.append(s)
    return world, slam, samples


@pytest.fixture(scope="module")
def house_run():
    return drive_the_house()


def test_the_trajectory_beats_the_odometry_by_far(house_run):
    world, slam, samples = house_run
    truth = {s.t: s.truth for s in samples}
    traj = slam.trajectory()
    assert len(traj) > 80 and all(t in truth for t, *_ in traj)
    err = np.array([math.hypot(x - truth[t][0], y - truth[t][1]) for t, x, y, _ in traj])
    rms = float(np.sqrt(np.mean(err**2)))
    o0, x0 = samples[0].odom, samples[0].truth
    odom = np.array([math.dist(compose(x0, relative(o0, s.odom))[:2], s.truth[:2]) for s in samples])
    odom_rms = float(np.sqrt(np.mean(odom**2)))
    assert odom_rms > 1.0  # the odometry alone is lost in the house
    assert rms < 0.25 and rms < 0.15 * odom_rms
    # the loop closes: the end is where it started
    assert math.dist(slam.pose()[:2], samples[-1].truth[:2]) < 0.1
    assert slam.loop_closures >= 1


def test_map_to_odom_and_pose_agree(house_run):
    world, slam, samples = house_run
    m2o = slam.map_to_odom()
    assert compose(m2o, samples[-1].odom) == pytest.approx(slam.pose(), abs=1e-9)


def test_the_map_has_the_walls_where_they_are(house_run):
    world, slam, samples = house_run
    m = slam.map()
    assert m.resolution == 0.05 and set(np.unique(m.data)) <= {-1, 0, 100}
    xs, ys = m.cell_centres(m.occupied())
    near = world.boxes.contains(xs, ys, margin=0.10)
    assert len(xs) > 800 and near.mean() > 0.75
    # the free space is inside the house and mostly off the furniture
    fx, fy = m.cell_centres(m.free())
    inside_boxes = world.boxes.contains(fx, fy).mean()
    outside = 1 - ((fx > -0.1) & (fx < 10.1) & (fy > -0.1) & (fy < 8.1)).mean()
    print(f"occupied near a box {near.mean():.3f}, free in a box {inside_boxes:.3f}, free outside {outside:.3f}")
    assert inside_boxes < 0.06 and outside < 0.03


def test_a_slam_without_scans_is_its_odometry():
    slam = Slam()
    angles = np.linspace(0, 2 * math.pi, 360, endpoint=False)
    for k in range(10):
        slam.add((0.1 * k, 0.0, 0.0), np.full(360, np.inf), angles, 3.5, t=k)
    assert slam.pose() == pytest.approx((0.9, 0.0, 0.0))
    assert slam.map_to_odom() == pytest.approx((0.0, 0.0, 0.0))
    assert len(slam.trajectory()) == 5 and slam.loop_closures == 0


def test_matching_returns_near_the_cut_are_not_biased_short():
    """A round room of radius 3.0 m, the cut at 3.0 m, 9 cm noise: cutting on each return's
    own range would keep the short ones (mean about 2.93 m); the cut by the neighbours'
    ranges keeps an unbiased half."""
    from navstack.slam import _Scan, match_points

    rng = np.random.default_rng(3)
    angles = np.linspace(0, 2 * math.pi, 3600, endpoint=False)
    ranges = 3.0 + rng.normal(0, 0.09, angles.size)
    # the room's radius drifts slowly around the cut, as a wall seen obliquely does
    ranges += 0.05 * np.sin(4 * angles)
    pts = match_points(_Scan(ranges.astype(np.float32), angles, 3.5, 0.12), 3.0, (0.0, 0.0, 0.0))
    kept = np.hypot(pts[:, 0], pts[:, 1])
    true_kept = 3.0 + 0.05 * np.sin(4 * np.arctan2(pts[:, 1], pts[:, 0]))
    own_cut = ranges[ranges < 3.0] - (3.0 + 0.05 * np.sin(4 * angles[ranges < 3.0]))
    assert 0.3 < len(kept) / angles.size < 0.7
    assert abs(float(np.mean(kept - true_kept))) < 0.01 < abs(float(np.mean(own_cut)))


def test_a_loop_closure_must_be_a_drift_the_travel_allows():
    slam = Slam()
    here = (2.0, 1.0, 0.3)
    assert slam._plausible_correction(here, compose(here, (0.08, 0.0, 0.01)), travelled=4.0)
    assert not slam._plausible_correction(here, compose(here, (0.40, 0.0, 0.0)), travelled=4.0)  # the wrong wall
    assert slam._plausible_correction(here, compose(here, (0.40, 0.0, 0.0)), travelled=30.0)  # after a long loop
    assert not slam._plausible_correction(here, compose(here, (0.0, 0.0, 0.3)), travelled=4.0)


def test_the_grid_is_rebuilt_only_when_a_closure_moved_the_keyframes(house_run):
    _, slam, _ = house_run
    slam.rebuild_map()
    assert not slam._map_moved()
    poses = slam.graph._poses
    saved = list(poses)
    try:
        poses[len(poses) // 2] = compose(saved[len(poses) // 2], (0.01, 0.0, 0.0))
        assert not slam._map_moved()  # a centimetre: the map stands
        poses[len(poses) // 2] = compose(saved[len(poses) // 2], (0.05, 0.0, 0.0))
        assert slam._map_moved()
    finally:
        poses[:] = saved


def test_a_map_published_while_mapping_is_rebuilt_at_most_every_rebuild_period(house_run):
    _, slam, _ = house_run
    slam.rebuild_map()
    poses = slam.graph._poses
    saved = list(poses)
    try:
        poses[-1] = compose(saved[-1], (0.10, 0.0, 0.0))
        slam._dirty = slam._map_moved()
        assert slam._dirty
        slam.map(fresh=False)  # just rebuilt: the grid stays as it is
        assert slam._dirty
        slam._t += slam.params.rebuild_period
        slam.map(fresh=False)
        assert not slam._dirty
        poses[-1] = saved[-1]
        slam._dirty = slam._map_moved()
        slam.map()  # fresh (save_map): rebuilt whatever the time
        assert not slam._dirty
    finally:
        poses[:] = saved


def test_a_keyframes_scans_line_up_in_its_reference_despite_a_heading_drift():
    # exact scans, odometry whose heading drifts 3 deg/s: a keyframe's later scans placed
    # by the odometry alone would be turned by up to a degree; the graph's heading corrects them
    from navstack.scan_matcher import transform
    from navstack.slam import match_points
    from navstack.synthetic import LaserSpec, OdomSpec

    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(
        occ,
        world_boxes(FIXTURES / "house_world.yaml"),
        seed=0,
        start=0,
        reverse=False,
        laser=LaserSpec(sigma_min=0.0, sigma_rel=0.0, dropout=0.0),
        scan_period=0.05,
        odom=OdomSpec(scale=0.0, turn_scale=0.0, drift=math.radians(3.0), sigma_v=0.0, sigma_w=0.0),
    )
    slam = Slam(SlamParams(initial_pose=world.truth, sensor_offset=world.laser.pose, loop_min_travel=1e9))
    truth = {}
    while world.t < 12:
        s = world.step()
        if s.scan is not None:
            slam.add(s.odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min)
            truth[s.t] = s.truth
    worst_raw = worst = 0.0
    for i in range(1, len(slam.keyframes) - 1):
        kf = slam.keyframes[i]
        if len(kf.scans) < 3 or any(abs(d[2]) > slam.params.pair_scan_turn for d, _ in kf.scans):
            continue
        ref, _ = slam._pair_reference(i)
        true = np.vstack(
            [
                transform(
                    relative(truth[kf.t], truth[scan.t]),
                    match_points(scan, slam.params.match_max_range, world.laser.pose),
                )
                for _, scan in kf.scans
            ]
        )
        raw = np.vstack(
            [transform(d, match_points(scan, slam.params.match_max_range, world.laser.pose)) for d, scan in kf.scans]
        )
        worst = max(worst, float(np.abs(ref - true).max()))
        worst_raw = max(worst_raw, float(np.abs(raw - true).max()))
    assert worst_raw > 0.02  # the drift's smear, uncorrected
    assert worst < 0.5 * worst_raw and worst < 0.015


def _wedged_run(track_scans: bool) -> list[float]:
    """The robot drives 6 s, then is wedged against furniture for 20 s: it stands still
    while its wheels spin (the odometry runs on at 0.17 m/s). The published pose's error
    at each scan of the wedged part [m]."""
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=1, start=0, reverse=False)
    slam = Slam(SlamParams(initial_pose=world.truth, sensor_offset=world.laser.pose, track_scans=track_scans))
    s = None
    while world.t < 6.0:
        s = world.step()
        if s.scan is not None:
            slam.add(s.odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min)
    odom, t, errors = s.odom, s.t, []
    for _ in range(100):  # 20 s of 5 Hz scans
        t += 0.2
        odom = compose(odom, (0.17 * 0.2, 0.0, 0.0))
        scan = world.scan()
        slam.add(odom, scan.ranges, scan.angles, scan.range_max, t, scan.range_min)
        errors.append(math.dist(slam.pose()[:2], world.truth[:2]))
    return errors


def test_the_published_pose_follows_the_laser_when_the_wheels_slip():
    tracked = np.array(_wedged_run(track_scans=True))
    # (the tracking's guess, once the wheels slipped, leaves out their distance: with it
    # the worst was 5.3 cm)
    assert np.sqrt(np.mean(tracked**2)) < 0.03 and tracked.max() < 0.045
    assert max(_wedged_run(track_scans=False)) > 0.2  # the odometry between keyframes


def _gyro_run(gyro: bool, scale: float = 1.015, seconds: float = 150.0, drift: float = 0.0, **params):
    """The synthetic house with an odometry whose heading is a gyro's: the true turns
    ``scale`` times too large (a gyro's scale error) plus ``drift`` [rad/s] (its bias),
    and the position integrated along it by the wheels' distance (as GyroOdometry does)."""
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=0, start=0, reverse=False)
    slam = Slam(SlamParams(initial_pose=world.truth, **params))
    heading, x, y, last, yaw_err = 0.0, 0.0, 0.0, None, []
    while world.target < len(world.tour) + 2 and world.t < seconds:
        s = world.step()
        if last is None:
            x, y, heading = s.odom
        else:
            turn = scale * math.remainder(s.truth[2] - last.truth[2], 2 * math.pi) + drift * (s.t - last.t)
            moved = relative(last.odom, s.odom)[0]  # the wheels' distance, forwards
            x += moved * math.cos(heading + turn / 2)
            y += moved * math.sin(heading + turn / 2)
            heading += turn
        last = s
        if s.scan is not None:
            odom = (x, y, heading)
            slam.add(odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min, gyro=gyro)
            yaw_err.append(math.remainder(slam.pose()[2] - s.truth[2], 2 * math.pi))
    return slam, float(np.sqrt(np.mean(np.square(yaw_err))))


def test_a_gyros_heading_links_the_keyframes_and_its_scale_error_is_learned():
    # (the walls' direction, which holds the heading too, left out)
    with_gyro, yaw_rms = _gyro_run(gyro=True, wall_heading=False)
    without, yaw_rms_matches = _gyro_run(gyro=False, wall_heading=False)
    kinds = {e.kind for e in with_gyro.graph.edges}
    assert "gyro" in kinds and "gyro" not in {e.kind for e in without.graph.edges}
    correction, sigma = with_gyro.gyro_scale()
    assert correction == pytest.approx(1 / 1.015 - 1, abs=0.004) and sigma < 0.004
    print(
        f"heading RMS {math.degrees(yaw_rms):.2f} deg with the gyro's links, "
        f"{math.degrees(yaw_rms_matches):.2f} without"
    )
    assert yaw_rms < yaw_rms_matches


def test_the_walls_direction_holds_the_heading_of_a_drifting_gyro():
    # a gyro bias of 0.01 deg/s, never taken off: 1.5 degrees in the run
    drift = math.radians(0.01)
    with_walls, yaw_rms = _gyro_run(gyro=True, scale=1.0, drift=drift)
    without, yaw_rms_gyro = _gyro_run(gyro=True, scale=1.0, drift=drift, wall_heading=False)
    assert len(with_walls.graph.directions) > 0.8 * len(with_walls.keyframes)
    assert not without.graph.directions
    assert abs(math.remainder(with_walls.graph.direction, math.pi / 2)) < math.radians(0.5)  # the house is square
    print(f"heading RMS {math.degrees(yaw_rms):.2f} deg with the walls, {math.degrees(yaw_rms_gyro):.2f} without")
    assert yaw_rms < math.radians(0.5) and yaw_rms < 0.7 * yaw_rms_gyro


def test_the_wheels_scale_is_learned_and_links_the_keyframes():
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=0, start=0, reverse=False)
    slam = Slam(SlamParams(initial_pose=world.truth))
    odo = truth = 0.0
    last = None
    while world.t < 120:
        s = world.step()
        if last is not None:
            odo += math.dist(s.odom[:2], last.odom[:2])
            truth += math.dist(s.truth[:2], last.truth[:2])
        last = s
        if s.scan is not None:
            slam.add(s.odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min)
    scale, sigma = slam.wheel_scale()
    assert abs(odo / truth - 1) > 0.01  # the synthetic odometry's distance is off
    print(f"wheel scale {scale:.4f} +- {sigma:.4f}, truth / odometry {truth / odo:.4f}")
    assert sigma < 0.006 and scale * odo / truth == pytest.approx(1.0, abs=0.006)
    wheels = [e for e in slam.graph.edges if e.kind == "wheels"]
    assert len(wheels) > 0.5 * len(slam.keyframes)
    assert all(e.info[2, 2] == 0.0 for e in wheels)  # distance only: the heading is the gyro's and the matches'
    # every link by the wheels has the scale learnt since, not the one known when it was made
    for e in wheels:
        o = relative(slam.keyframes[e.i].odom, slam.keyframes[e.j].odom)
        assert math.hypot(*e.z[:2]) == pytest.approx(scale * math.hypot(*o[:2]), abs=1e-9)


def test_a_local_map_match_that_slid_away_from_the_wheels_is_not_a_keyframes_pose():
    # One keyframe's match against the local map slides 25 cm along x (as it does along a
    # wall that pins only the other axis); the matches against the keyframes before it,
    # and the wheels, which held, put it where it is.
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=0, start=0, reverse=False)
    slam = Slam(SlamParams(initial_pose=world.truth, sensor_offset=world.laser.pose))
    match_local, slid = slam._match_local, {}

    def sliding(pts, predicted):
        matched, cov = match_local(pts, predicted)
        if matched is not None and not slid and world.t > 20.0:
            slid["keyframe"] = len(slam.keyframes)
            matched = (matched[0] + 0.25, matched[1], matched[2])
        return matched, cov

    slam._match_local = sliding
    truth_at = {}
    while world.t < 30.0:
        s = world.step()
        if s.scan is not None:
            truth_at[s.t] = s.truth
            slam.add(s.odom, s.scan.ranges, s.scan.angles, s.scan.range_max, s.t, s.scan.range_min)
    k = slid["keyframe"]
    assert {e.kind for e in slam.graph.edges if e.j == k} >= {"pair", "wheels"}
    assert math.dist(slam.graph.pose(k)[:2], truth_at[slam.keyframes[k].t][:2]) < 0.05


def test_icp_on_what_the_reference_saw_shrinks_the_pair_links_less():
    # A match pulls the returns the reference never saw (round a corner, past furniture)
    # onto what it did see, which lies back towards it, and Gauss-Newton on a blurred map
    # pulls the returns at a wall's end inwards: in this run the default links are 11.0 mm/m
    # short, those of pair_match="icp_visible" 7.9 mm/m.
    world, slam, samples = drive_the_house(pair_match="icp_visible")
    truth = {s.t: s.truth for s in samples}
    kf_true = [truth[kf.t] for kf in slam.keyframes]
    along, length = 0.0, 0.0
    for e in slam.graph.edges:
        zt = relative(kf_true[e.i], kf_true[e.j])
        n = math.hypot(zt[0], zt[1])
        if e.kind == "pair" and n > 0.05:
            along += ((e.z[0] - zt[0]) * zt[0] + (e.z[1] - zt[1]) * zt[1]) / n
            length += n
    assert length > 20 and abs(along / length) < 0.009
    assert math.dist(slam.pose()[:2], world.truth[:2]) < 0.1


def test_a_return_behind_what_the_laser_saw_is_not_seen():
    from navstack.slam import _Scan, _seen_from

    angles = np.radians(np.arange(360.0))
    scan = _Scan(np.full(360, 2.0, dtype=np.float32), angles, 3.5, 0.12)  # a round room, 2 m
    q = np.array([[1.0, 0.0], [2.05, 0.0], [0.0, 2.5], [-3.0, 0.0]])  # the laser at the origin
    assert _seen_from(scan, q, (0.0, 0.0, 0.0), (0.01, 0.03)).tolist() == [True, True, False, False]


def test_an_unknown_pair_match_is_refused():
    with pytest.raises(ValueError, match="pair_match"):
        Slam(SlamParams(pair_match="icp"))
