"""2-D graph SLAM from odometry and a laser: keyframes, scan matching, loop closure.

:class:`Slam` takes, per scan, the odometry pose and the scan (:meth:`Slam.add`) and keeps

* **keyframes**: a scan becomes one once the odometry says the robot moved more than
  ``keyframe_dist`` or turned more than ``keyframe_angle`` since the last. A keyframe is
  matched against the *local map*, the returns of the keyframes of the last
  ``loop_min_travel`` metres of travel (at most ``local_keyframes``) at their current
  poses: :class:`~navstack.scan_matcher.CorrelativeMatcher` on a 5 cm likelihood map,
  then :func:`~navstack.scan_matcher.refine` (Gauss-Newton) on a 2 cm density map of the
  same returns, weighted by 1 / range noise^2 (:func:`match_points`: which returns).
  Matching against the recent stretch only (not the whole map) keeps an old, drifted part
  of the map from pulling the robot before the loop is closed explicitly;
* **tracking** (``track_scans``): each scan between keyframes is matched against the newest
  keyframe's returns, in a small window around the last scan's pose plus the odometry
  since. :meth:`Slam.pose` (what the mapper publishes) and the next keyframe's guess
  follow these matches (or the wheels, below, while the two agree), and keyframes are
  spaced by them: wheels that slip, or spin while the robot is wedged against
  furniture, move neither. Along an axis where the match is loose (a wall or two) the
  odometry's;
* **a pose graph** (:class:`~navstack.pose_graph.PoseGraph`): per keyframe, links to the
  ``pair_edges`` keyframes before it and to the ``near_links`` nearest ones of the local
  stretch (a turn on the spot links back to where it began, not through a chain of
  links whose heading noise adds up), each a Gauss-Newton match against that keyframe's
  returns alone (all its scans, placed by the odometry unless the wheels slipped: short
  baselines, little shrink); else a match edge (the matcher's covariance) from the
  previous keyframe, or an odometry edge (uncertainty growing with the distance and the
  turn) where the match failed; and where the odometry's heading is a gyro's, a
  heading-only link to the previous keyframe by its turn (``gyro_links``), its scale
  error learnt from the pair links;
* **the wheels** (``wheel_links``): their distance times a scale learnt from the matches
  links each keyframe to the last and carries the pose between keyframes, unless the
  tracking saw them slip: a match in a room with little across the way wanders by
  centimetres, the wheels by millimetres;
* **the walls' direction** (``wall_heading``): each keyframe's heading is linked, modulo 90
  degrees, to the direction of the walls its scan sees (:mod:`navstack.wall_heading`),
  one unknown angle shared by all keyframes: indoors most walls are parallel or
  perpendicular, so the heading cannot drift while the robot explores rooms with no loop
  to close;
* **loop closures**: a keyframe is matched against the submap around an old keyframe
  (``loop_min_travel`` back along the path but within ``loop_radius``), over a wide window;
  a good score, a refinement that stays within ``loop_max_refine_shift`` and a
  correction no larger than the travel since allows (``loop_gate_xy``, ``loop_gate_yaw``)
  add a loop edge, the graph is optimised (Cauchy loss, against a wrong closure) and
  every keyframe moves;
* **the map**: a :class:`~navstack.log_odds.LogOddsGrid`. Each scan is integrated at its
  pose when it arrives; after a loop closure that moved a keyframe more than
  ``rebuild_shift`` from where its scans were mapped, the grid is rebuilt from the stored
  scans at the corrected poses (lazily, on the next :meth:`Slam.map`).

Frames: ``odom`` is the odometry's frame, ``map`` SLAM's; the first keyframe is at
``initial_pose`` in the map (default: its odometry pose, so map = odom at the start).
The laser sits at ``sensor_offset`` (x [m], y [m], yaw [rad]) in the base frame: the
TurtleBot3's LDS-01 ``base_scan`` is 0.15 m behind ``base_footprint``.

Poses are (x [m], y [m], yaw [rad]); times [s].
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .log_odds import LogOddsGrid, LogOddsParams
from .map_io import OccupancyMap
from .odometry import as_pose
from .pose_graph import PoseGraph, compose, relative
from .scan_matcher import (
    CorrelativeMatcher,
    IcpReference,
    LikelihoodMap,
    MatcherParams,
    icp,
    refine,
    scan_points,
    transform,
)
from .wall_heading import nearest_turn, wall_direction

IDENTITY = (0.0, 0.0, 0.0)


@dataclass
class SlamParams:
    resolution: float = 0.05  # map cells [m]
    sensor_offset: tuple = (-0.15, 0.0, 0.0)  # the laser in the base frame (TB3 LDS-01)
    initial_pose: tuple | None = None  # the first keyframe in the map; None: its odometry
    keyframe_dist: float = 0.2  # [m]
    keyframe_angle: float = math.radians(15)  # [rad]
    # the front end
    local_keyframes: int = 20  # the local map: at most N keyframes' returns
    match_window_xy: float = 0.25  # [m] around the odometry's prediction
    match_window_yaw: float = math.radians(10)
    match_sigma: float = 0.05  # the likelihood map's spread [m]
    match_max_range: float = 3.0  # match only returns nearer than this [m]: near
    #   range_max, only the returns whose noise made them short survive (biased towards the laser)
    min_match_score: float = 0.35  # below: trust the odometry
    track_scans: bool = True  # match every scan against the newest keyframe:
    #   the pose published between keyframes, and the next keyframe's guess, follow the laser,
    #   not the odometry (whose wheels slip, or spin while the robot is wedged against furniture)
    track_window_xy: float = 0.1  # its search window around the last scan's pose
    #                                           plus the odometry since [m]
    track_window_yaw: float = math.radians(1)  # (the gyro holds the heading over a scan)
    track_max_sigma: float = 0.03  # a looser match (its covariance's widest) keeps
    #                                           the odometry's [m]
    slip_tolerance: float = 0.03  # a scan whose match is this far from the odometry's
    #   offset [m] goes into the map and the links' references at its match; else at the
    #   odometry's (matches are shrunk towards their reference by a per cent or two)
    pair_edges: int = 3  # link each keyframe to the N before it, each
    #                                           matched alone (0: one link, the local-map match)
    pair_sigma: tuple = (0.03, math.radians(1.0))  # those links' sigma [m, rad]
    near_links: int = 3  # and to the N nearest keyframes of the local
    near_link_radius: float = 0.3  # stretch within this [m] (a turn on the spot)
    pair_all_scans: bool = True  # a link's reference: every scan of the older
    #   keyframe (each at its odometry offset), not only its first: 3-5 noisy scans of the same
    #   walls average out, and the links' shrink and heading noise drop (bench/mapping_replay.py)
    pair_match: str = "icp_visible"  # the pair links' match: "icp_visible" (point-to-line
    #   ICP on the returns the keyframe's beams reach, by 3 sigma of the noise) or
    #   "gauss_newton" (on the keyframe's density map: its links come out 1.5 % short, as
    #   the returns' density falls off along a wall, so the map shrinks by as much)
    pair_scan_turn: float = math.radians(5)  # but only the scans turned at most this much from it
    gyro_links: bool = True  # link each keyframe's heading to the last's by the
    #   odometry's turn where that is the gyro's (Slam.add's ``gyro``; GyroOdometry takes the
    #   bias off at each stop)
    gyro_sigma: tuple = (math.radians(0.03), 0.005, math.radians(0.005))  # its sigma: floor [rad],
    #   per radian turned (what is left of the gyro's scale error once estimated), per second
    #   (its bias left after a stop) [rad/s]
    gyro_scale_prior: float = 0.02  # the gyro's scale error before any turn [sigma]
    wheel_links: bool = True  # trust the wheels' distance times their scale, as learnt
    #   from the pair links (a wheel radius is off by a per cent or two; once that is known,
    #   the wheels measure 20 cm to a few millimetres, better than a match along a room with
    #   little across the way): link each keyframe to the last by it and follow it between
    #   keyframes, unless the tracking saw the wheels slip, and place a keyframe's later
    #   scans by it (a 2 % error smears the pair links' references)
    wheel_sigma: tuple = (0.002, 0.01)  # those links' sigma: floor [m], per metre
    wheel_match_sigma: float = 0.01  # a match's distance to the last keyframe, as the scale's
    #   evidence [m]: a metre of steps gives the scale to 2 %, ten metres to 0.6 %
    track_slip: float = 0.05  # the tracking says the wheels slipped: it is further than
    #   this from them since the newest keyframe [m] (along the axes where it is firm)
    wall_heading: bool = True  # link each keyframe's heading to the walls' direction
    #   (modulo 90 degrees), one unknown that every keyframe's scan measures: most indoor walls
    #   are parallel or perpendicular, and that heading does not drift between loop closures
    #   (navstack.wall_heading); walls further off than the gate (at an angle) add nothing
    wall_heading_sigma: tuple = (math.radians(0.1), 2.0)  # its sigma: floor [rad], and
    #   the factor on the lines' own scatter (the returns' noise is not all white)
    wall_heading_gate: float = math.radians(1.5)  # further than this from the graph's heading
    #   (plus 3 sigma): another direction (a wall at an angle, furniture), not the walls'
    optimize_every: int = 1  # keyframes between two graph optimisations
    #   when pair_edges > 0 (every one: the published pose is the newest keyframe's, which
    #   stands at its local-map match until the graph takes its links in)
    refine: str = "gauss_newton"  # off the lattice: "gauss_newton" (on a fine density
    #                                           map of the local returns), "icp" or "none"
    refine_resolution: float = 0.02  # that map's cells [m]
    refine_sigma: float = 0.04  # and its blur [m]
    range_noise: tuple = (0.01, 0.03)  # the laser's sigma: max(a [m], b * range); weighs
    #                                           the local map's returns by 1 / sigma^2
    # odometry edges: standard deviations per metre travelled / per radian turned, with floors
    # (loose: wheel odometry's errors are systematic - scale, heading drift - not white)
    odom_xy_per_m: float = 0.1
    odom_yaw_per_m: float = math.radians(5.0)
    odom_yaw_per_rad: float = 0.1
    odom_floor: tuple = (0.01, 0.01, math.radians(1.0))
    # loop closure
    loop_min_travel: float = 4.0  # only keyframes this far back along the path [m]
    loop_radius: float = 1.0  # and this near in space [m]
    loop_window_xy: float = 0.8  # search window [m]
    loop_window_yaw: float = math.radians(20)
    loop_submap: int = 6  # the old keyframe's submap: +- this many keyframes
    loop_min_score: float = 0.55  # accept at this mean likelihood or more
    loop_max_refine_shift: float = 0.1  # the refinement may not move the match more [m]
    loop_cov_scale: float = 4.0  # loop edges' covariance x this (they are riskier)
    loop_candidates: int = 2  # old keyframes tried per keyframe
    loop_cooldown: int = 3  # keyframes between two closures
    rebuild_shift: float = 0.025  # rebuild the grid once the graph moved a
    #                                           keyframe this much [m] from where it was mapped
    rebuild_period: float = 10.0  # [s] of scans between two rebuilds, map(fresh=False)
    loop_gate_xy: tuple = (0.05, 0.02)  # a closure may move the keyframe by at most
    loop_gate_yaw: tuple = (math.radians(2.0), math.radians(0.3))  # a + b * metres travelled since
    # the map
    map_all_scans: bool = True  # every scan, not only keyframes
    grid: LogOddsParams = field(default_factory=lambda: LogOddsParams(far_range=3.0, l_occ=0.55, l_free=-0.3))
    #   returns beyond 3 m (9 cm noise) count less; and it takes two returns to mark a cell
    #   (p 0.63 after one, 0.75 after two): a lone return that its noise put behind a wall
    #   stays there (no later beam crosses that cell), a speckle outside the house


@dataclass
class Keyframe:
    t: float
    odom: tuple  # its odometry pose (odom frame)
    points: np.ndarray  # (K, 2) returns in the base frame [m]
    weights: np.ndarray  # (K,) their weight in a local map: 1 / range noise^2, relative
    travel: float  # odometry path length from the start [m]
    gyro: bool = False  # its odometry's heading is the gyro's
    scans: list = field(default_factory=list)  # (relative pose to this keyframe, scan) to rebuild the map
    density: LikelihoodMap | None = None  # of its returns, for pair edges (lazily, once complete)
    pair_icp: IcpReference | None = None  # its returns for pair_match "icp_visible" (lazily, once complete)
    scan_icp: IcpReference | None = None  # its own scan's returns alone, for the wheels' scale (lazily)


@dataclass
class _LocalMap:
    key: tuple  # (keyframes, graph version) it was built for
    points: np.ndarray  # (N, 2) its returns in the map frame
    coarse: LikelihoodMap  # for the correlative matcher
    fine: LikelihoodMap | None  # the density map for the Gauss-Newton refinement


@dataclass
class _Scan:
    ranges: np.ndarray
    angles: np.ndarray
    range_max: float
    range_min: float
    t: float = 0.0


PAIR_MATCHES = ("gauss_newton", "icp_visible")


class Slam:
    """Keyframe graph SLAM. Feed :meth:`add`; read :meth:`pose`, :meth:`map`, :meth:`trajectory`."""

    def __init__(self, params: SlamParams | None = None):
        self.params = p = params or SlamParams()
        if p.pair_match not in PAIR_MATCHES:
            raise ValueError(f"SlamParams.pair_match must be one of {PAIR_MATCHES}, not {p.pair_match!r}")
        if p.grid.resolution != p.resolution:
            p.grid = LogOddsParams(**{**p.grid.__dict__, "resolution": p.resolution})
        self.graph = PoseGraph()
        self.keyframes: list[Keyframe] = []
        self.grid = LogOddsGrid(p.grid)
        self.matcher = CorrelativeMatcher(MatcherParams(window_xy=p.match_window_xy, window_yaw=p.match_window_yaw))
        self.loop_closures = 0
        self.last_match_score = float("nan")
        self._odom = IDENTITY  # the latest odometry pose
        self._travel = 0.0
        self._dirty = False  # the grid predates the latest loop closure
        self._integrated_at: list[tuple] = []  # per keyframe, the pose its scans were mapped at
        self._t = self._rebuilt_t = 0.0  # the latest scan's time, the last rebuild's [s]
        self._since_closure = 1 << 30
        self._track_offset = IDENTITY  # the latest scan's pose from the newest keyframe
        self._track_odom = IDENTITY  # and the odometry there
        self._wheel_offset = IDENTITY  # the latest scan's pose from the newest keyframe by the wheels
        self._slipped = False  # the tracking found the wheels slipping since the newest keyframe
        self._local_map: _LocalMap | None = None
        self._kf_map: _LocalMap | None = None
        self._graph_version = 0  # bumped whenever the graph moves its nodes
        self._turns = [0.0, 0.0]  # the gyro's scale from the matches: sum g^2, sum (m - g) g
        self._wheel = [0.0, 0.0]  # the wheels' from the matches: sum d^2, sum m d
        self._wheel_edges: list = []  # [(edge, its odometry step)]: rescaled as the scale is learnt
        self._wheel_links_scale: tuple | None = None  # the wheel_scale() they were last rescaled to
        self._gyro = False  # the latest odometry's heading is the gyro's

    # -- input ---------------------------------------------------------------------------------
    def add(
        self, odom_pose, ranges, angles, range_max: float, t: float = 0.0, range_min: float = 0.0, gyro: bool = False
    ) -> bool:
        """Take one scan and the odometry pose (x [m], y [m], yaw [rad], odom frame) at its
        time ``t`` [s]. ``ranges`` [m] and ``angles`` [rad, sensor frame] are the beams;
        inf or >= ``range_max`` is no return. ``gyro``: the odometry's heading is a gyro's
        (see :attr:`SlamParams.gyro_links`). Returns True when it became a keyframe."""
        p = self.params
        odom = as_pose(odom_pose)
        self._t = float(t)
        self._gyro = bool(gyro)
        # copies: a row of a caller's larger array would keep all of it alive
        scan = _Scan(
            np.array(ranges, dtype=np.float32),
            np.array(angles, dtype=np.float64),
            float(range_max),
            float(range_min),
            float(t),
        )
        if not self.keyframes:
            self._odom = self._track_odom = odom
            self._new_keyframe(t, odom, scan, p.initial_pose or odom)
            return True
        last = self.keyframes[-1]
        step = self._wheel_step(relative(self._track_odom, odom))
        self._wheel_offset = compose(self._wheel_offset, step)
        # the odometry's guess; once the wheels slipped, their turn alone (the gyro's): a
        # robot caught on something the laser does not see stays put while they spin on
        offset = compose(self._track_offset, (0.0, 0.0, step[2]) if self._slipped else step)
        if p.track_scans:
            offset = self._track(offset, scan)
            if p.wheel_links and not self._slipped:
                if math.hypot(offset[0] - self._wheel_offset[0], offset[1] - self._wheel_offset[1]) > p.track_slip:
                    self._slipped = True
                else:
                    offset = self._wheel_offset
        self._travel += math.hypot(offset[0] - self._track_offset[0], offset[1] - self._track_offset[1])
        self._odom, self._track_offset, self._track_odom = odom, offset, odom
        if math.hypot(offset[0], offset[1]) < p.keyframe_dist and abs(offset[2]) < p.keyframe_angle:
            if p.map_all_scans:
                delta = self._scan_delta(offset, relative(last.odom, odom))
                last.scans.append((delta, scan))
                self._integrate(compose(self.graph.pose(len(self.keyframes) - 1), delta), scan)
            return False
        self._new_keyframe(t, odom, scan, None, offset)
        self._track_offset = self._wheel_offset = IDENTITY
        self._slipped = False
        return True

    # -- output --------------------------------------------------------------------------------
    def pose(self) -> tuple:
        """The robot's (base frame's) pose in the map frame, at the latest odometry."""
        if not self.keyframes:
            return self.params.initial_pose or self._odom
        k = len(self.keyframes) - 1
        return compose(compose(self.graph.pose(k), self._track_offset), relative(self._track_odom, self._odom))

    def map_to_odom(self) -> tuple:
        """The map -> odom transform (x [m], y [m], yaw [rad]) that puts the odometry's
        latest pose on :meth:`pose`."""
        return compose(self.pose(), relative(self._odom, IDENTITY))

    def map(self, fresh: bool = True) -> OccupancyMap:
        """The occupancy grid so far as map_server's trinary map, rebuilt first if the graph
        moved the keyframes since. ``fresh=False`` (a map published every second) rebuilds
        at most every ``rebuild_period`` seconds of scan time: a rebuild costs a second or
        more on a house, and in between the grid is off by centimetres."""
        if self._dirty and (fresh or self._t - self._rebuilt_t >= self.params.rebuild_period):
            self.rebuild_map()
        return self.grid.to_map()

    def trajectory(self) -> list[tuple]:
        """The keyframes' corrected poses: [(t [s], x [m], y [m], yaw [rad])]."""
        return [(kf.t, *self.graph.pose(i)) for i, kf in enumerate(self.keyframes)]

    def rebuild_map(self) -> None:
        """Re-integrate every stored scan at its keyframe's current pose."""
        self._dirty = False
        self._rebuilt_t = self._t
        self._integrated_at = [tuple(x) for x in self.graph.poses]
        self.grid.clear()
        for i, kf in enumerate(self.keyframes):
            x = self.graph.pose(i)
            for delta, scan in kf.scans:
                self._integrate(compose(x, delta), scan)

    # -- the front end -------------------------------------------------------------------------
    def _new_keyframe(self, t: float, odom: tuple, scan: _Scan, pose, offset=None) -> None:
        """Make the scan a keyframe: at ``pose`` (the first), else matched from ``offset``
        (its pose guessed from the newest keyframe's)."""
        p = self.params
        pts = match_points(scan, p.match_max_range, p.sensor_offset)
        kf = Keyframe(t, odom, pts, self._weights(pts), self._travel, gyro=self._gyro, scans=[(IDENTITY, scan)])
        if pose is not None:  # the first keyframe
            self.graph.add_node(pose)
            self.keyframes.append(kf)
            if p.wall_heading:
                self._add_wall_heading(0, pts)
            self._integrated_at.append(tuple(pose))
            self._integrate(pose, scan)
            return
        k = len(self.keyframes)
        z_odom = offset
        predicted = compose(self.graph.pose(k - 1), z_odom)
        matched, cov = self._match_local(pts, predicted)
        self.graph.add_node(matched if matched is not None else predicted)
        self.keyframes.append(kf)
        self._integrated_at.append(self.graph.pose(k))  # (its scan goes in below)
        # The chain's links: the keyframe matched alone against each of the few before it,
        # from the local map's pose (short baselines: a match against a long stretch of map
        # is pulled back towards where that map was seen from, a shrink of a few per cent);
        # else the local-map match; the odometry only where matching failed (it slips
        # against obstacles, and as an extra link it pulls every good match off by its drift)
        pairs = self._pair_matches(k, pts, matched) if matched is not None and p.pair_edges else []
        if not pairs and matched is not None and p.pair_edges and self._wheels_held():
            # every pair match left the local map's pose: it slid along a wall, away from
            # where the wheels (which held) put the keyframe; the pairs may agree with them
            if math.hypot(matched[0] - predicted[0], matched[1] - predicted[1]) > p.track_slip:
                self.graph.set_pose(k, predicted)
                pairs = self._pair_matches(k, pts, predicted)
                if pairs:
                    matched = predicted
                else:
                    self.graph.set_pose(k, matched)
        sx, syaw = p.pair_sigma
        link_info = np.diag([1 / sx**2, 1 / sx**2, 1 / syaw**2])
        for i, z in pairs:
            self.graph.add_edge(i, k, z, link_info, "pair")
        if pairs:
            for i, z in self._near_matches(k, pts, matched):
                self.graph.add_edge(i, k, z, link_info, "near")
        if p.wheel_links:
            self._learn_wheel_scale(k, pairs)
            self._add_wheel_link(k)
        if p.gyro_links and kf.gyro and self.keyframes[k - 1].gyro:
            self._learn_gyro_scale(k, pairs)
            self._add_gyro_link(k)
        if p.wall_heading:
            self._add_wall_heading(k, pts)
        if not pairs and matched is not None:
            self.graph.add_edge(k - 1, k, relative(self.graph.pose(k - 1), matched), _information(cov), "match")
        elif not pairs:
            self.graph.add_edge(k - 1, k, z_odom, self._odom_information(z_odom), "odom")
        elif k % p.optimize_every == 0:
            self._rescale_wheel_links()
            self.graph.optimize(max_iterations=10, loss="cauchy", f_scale=3.0)
            self._graph_version += 1
            self._dirty = self._dirty or self._map_moved()
        self._since_closure += 1
        if self._since_closure > p.loop_cooldown and self._close_loop(k):
            self._since_closure = 0
        self._integrated_at[k] = self.graph.pose(k)
        self._integrate(self.graph.pose(k), scan)

    def _add_gyro_link(self, k: int) -> None:
        """Keyframe k's heading from k - 1's by the odometry's turn between them: the gyro
        holds the heading over a second to a few hundredths of a degree, several times
        better than a scan match (about a quarter of a degree). Heading only: the wheels'
        distance is the matches' business."""
        p = self.params
        a, b = self.keyframes[k - 1], self.keyframes[k]
        z = relative(a.odom, b.odom)
        correction, scale_sigma = self.gyro_scale()
        floor, per_rad, per_s = p.gyro_sigma
        sigma = math.sqrt(floor**2 + ((per_rad + scale_sigma) * z[2]) ** 2 + (per_s * (b.t - a.t)) ** 2)
        z = (z[0], z[1], z[2] * (1 + correction))
        self.graph.add_edge(k - 1, k, z, np.diag([1e-6, 1e-6, 1 / sigma**2]), "gyro")

    def _add_wall_heading(self, k: int, pts: np.ndarray) -> None:
        """Link keyframe k's heading to the walls' direction in the map (the graph's
        :attr:`~navstack.pose_graph.PoseGraph.direction`, first set by the first keyframe
        that saw walls) by the direction of its scan's walls in its base frame, at the
        multiple of 90 degrees nearest the graph's heading."""
        walls = self._wall_direction(pts)
        if walls is None:
            return
        p = self.params
        floor, factor = p.wall_heading_sigma
        sigma = math.hypot(floor, factor * walls.sigma)
        guess = self.graph.pose(k)[2]
        if not self.graph.directions:
            self.graph.direction = math.remainder(guess + walls.angle, math.pi / 2)
        z = nearest_turn(-walls.angle, guess - self.graph.direction)
        if abs(math.remainder(z - (guess - self.graph.direction), 2 * math.pi)) > p.wall_heading_gate + 3 * sigma:
            return
        self.graph.add_direction(k, z, sigma)

    def _wall_direction(self, pts: np.ndarray):
        return wall_direction(pts, self._range_sigma(pts))

    def gyro_scale(self) -> tuple[float, float]:
        """The factor the odometry's turns are off by, as the scan matches see it (a
        turn's true size is the odometry's times 1 + this), and its sigma."""
        gg, mg = self._turns
        match_sigma = self.params.pair_sigma[1] / 3  # a single match's, not the links' looser one
        prior = (match_sigma / self.params.gyro_scale_prior) ** 2  # no turn yet: no correction
        return mg / (gg + prior), match_sigma / math.sqrt(gg + prior)

    def wheel_scale(self) -> tuple[float, float]:
        """The factor the odometry's distances are off by, as the matches see them (a
        distance's true length is the odometry's times this), and its sigma: 1 +- 3 %
        before any travel (a wheel radius off by a per cent or two), then the least-squares
        ratio over the steps learnt from, each match good to ``wheel_match_sigma``."""
        dd, md = self._wheel
        prior = (self.params.wheel_match_sigma / 0.03) ** 2  # [m^2]
        return (md + prior) / (dd + prior), self.params.wheel_match_sigma / math.sqrt(dd + prior)

    def _learn_wheel_scale(self, k: int, pairs) -> None:
        """Add keyframe k's distance from k - 1 by the odometry and by matching to the
        wheels' scale (left out: a short step, or a match far off both: the wheels slipped).
        The match is against k - 1's own scan alone, not the pair link's reference: that
        one's later scans are placed by the wheels, so its match would carry a third of
        their scale error back into the scale."""
        o = relative(self.keyframes[k - 1].odom, self.keyframes[k].odom)
        z = next((z for i, z in pairs if i == k - 1), None)
        d = math.hypot(o[0], o[1])
        if z is None or d < 0.1:
            return
        prev = self.keyframes[k - 1]
        if prev.scan_icp is None:
            prev.scan_icp = IcpReference(prev.points, neighbours=10)
        z = self._align_visible(prev.scan_icp, prev.scans[0][1], self.keyframes[k].points, z)
        m = math.hypot(z[0], z[1])
        if abs(m - d) > 0.02 + 0.1 * d:
            return
        self._wheel[0] += d * d
        self._wheel[1] += m * d

    def _add_wheel_link(self, k: int) -> None:
        """Keyframe k from k - 1 by the odometry's distance times the learnt scale, on x
        and y alone (the heading is the matches' and the gyro's), as loose as the scale is
        uncertain (:meth:`_wheel_link`); none where the wheels slipped (:meth:`_wheels_held`)."""
        if not self._wheels_held():
            return
        o = relative(self.keyframes[k - 1].odom, self.keyframes[k].odom)
        edge = self.graph.add_edge(k - 1, k, *self._wheel_link(o, self.wheel_scale()), "wheels")
        self._wheel_edges.append((edge, o))

    def _rescale_wheel_links(self) -> None:
        """Every link by the wheels with the scale as it is learnt now: the scale known when
        a link was made (its first metres, in the first room) would leave the keyframes
        that nothing else ties back to where the scale put them. Nothing to do while the
        scale has not changed since the last time (the newer links were made with it)."""
        scale = self.wheel_scale()
        if scale == self._wheel_links_scale:
            return
        self._wheel_links_scale = scale
        for edge, o in self._wheel_edges:
            edge.z, edge.info = self._wheel_link(o, scale)

    def _wheel_link(self, o, scale: tuple[float, float]) -> tuple[tuple, np.ndarray]:
        """A link by the wheels for the odometry step ``o``: its distance times the learnt
        ``scale`` (factor, sigma: :meth:`wheel_scale`), and x and y's information (sigma
        ``wheel_sigma`` plus the scale's own per metre; none on the heading)."""
        p = self.params
        factor, scale_sigma = scale
        sigma = p.wheel_sigma[0] + (p.wheel_sigma[1] + scale_sigma) * math.hypot(o[0], o[1])
        return (factor * o[0], factor * o[1], o[2]), np.diag([1 / sigma**2, 1 / sigma**2, 0.0])

    def _wheels_held(self) -> bool:
        """Whether the wheels did not slip since the newest keyframe: the tracking matches
        stayed within ``track_slip`` of them (with ``wheel_links`` and ``track_scans``)."""
        p = self.params
        return p.wheel_links and p.track_scans and not self._slipped

    def _wheel_step(self, step) -> tuple:
        """An odometry step with its distance times the wheels' learnt scale (with
        ``wheel_links``)."""
        if not self.params.wheel_links:
            return step
        scale = self.wheel_scale()[0]
        return (scale * step[0], scale * step[1], step[2])

    def _learn_gyro_scale(self, k: int, pairs) -> None:
        """Add keyframe k's turn from k - 1, by the odometry and by its pair link, to the
        scale's estimate (a match far off both is left out: a wrong match)."""
        g = relative(self.keyframes[k - 1].odom, self.keyframes[k].odom)[2]
        m = next((z[2] for i, z in pairs if i == k - 1), None)
        if m is None or abs(g) < math.radians(2):
            return
        if abs(m - g) > math.radians(1.0) + 0.05 * abs(g):
            return
        self._turns[0] += g * g
        self._turns[1] += (m - g) * g

    def _match_local(self, pts: np.ndarray, predicted):
        """The keyframe's pose from the local map, and its covariance; (None, None) when
        the match is too poor to trust."""
        p = self.params
        if len(pts) < 20:
            return None, None
        local = self._local()
        res = self.matcher.match(local.coarse, pts, predicted)
        self.last_match_score = res.score
        if res.score < p.min_match_score:
            return None, None
        return self._refine_local(local, pts, res.pose), res.covariance

    def _track(self, offset, scan: _Scan) -> tuple:
        """A scan's pose from the newest keyframe, matched against that keyframe's returns
        in a small window around ``offset`` (the last scan's plus the odometry since).
        Along an axis where the match is loose (wider than ``track_max_sigma``: a wall or
        two, it slides along them) ``offset``'s, and ``offset`` itself when the match is
        too poor or loose both ways. Against the keyframe alone, not the local map: a
        short baseline, no shrink, and the keyframe's own place in the map is the graph's
        business."""
        p = self.params
        pts = match_points(scan, p.match_max_range, p.sensor_offset)
        if len(pts) < 20 or len(self.keyframes[-1].points) < 20:
            return offset
        ref = self._keyframe_map()
        res = self.matcher.match(ref.coarse, pts, offset, p.track_window_xy, p.track_window_yaw)
        if res.score < p.min_match_score:
            return offset
        values, axes = np.linalg.eigh(res.covariance[:2, :2])
        firm = values <= p.track_max_sigma**2
        if not firm.any():
            return offset
        matched = self._refine_local(ref, pts, res.pose)
        if firm.all():
            return matched
        axis = axes[:, 0]  # the firm one: the match's along it, the guess's across
        shift = (matched[0] - offset[0]) * axis[0] + (matched[1] - offset[1]) * axis[1]
        return (offset[0] + shift * axis[0], offset[1] + shift * axis[1], matched[2])

    def _scan_delta(self, tracked, by_odometry) -> tuple:
        """Where a keyframe's later scan goes, from the keyframe: the odometry's offset
        (its distance times the wheels' learnt scale; a match's is shrunk towards the
        reference, by a per cent or two) unless the wheels slipped, i.e. the match
        disagrees with it by more than ``slip_tolerance``."""
        by_odometry = self._wheel_step(by_odometry)
        slipped = math.hypot(tracked[0] - by_odometry[0], tracked[1] - by_odometry[1]) > self.params.slip_tolerance
        return tracked if slipped else by_odometry

    def _keyframe_map(self) -> _LocalMap:
        """The newest keyframe's returns in its own frame, as the matchers' maps (built
        once per keyframe)."""
        key = (len(self.keyframes), -1)
        if self._kf_map is None or self._kf_map.key != key:
            p = self.params
            kf = self.keyframes[-1]
            fine = LikelihoodMap.from_density(
                kf.points, p.refine_resolution, p.refine_sigma, levels=0, weights=kf.weights
            )
            self._kf_map = _LocalMap(
                key, kf.points, LikelihoodMap.from_points(kf.points, p.resolution, p.match_sigma), fine
            )
        return self._kf_map

    def _refine_local(self, local: _LocalMap, pts: np.ndarray, pose) -> tuple:
        """The lattice pose refined off it on the local map (:attr:`SlamParams.refine`);
        a refinement that leaves the lattice cell it started from is not trusted."""
        p = self.params
        if p.refine == "gauss_newton":
            assert local.fine is not None  # the local maps have it whenever refine is "gauss_newton"
            refined = refine(local.fine, pts, pose)[0]
        elif p.refine == "icp":
            refined = self._refine(local.points, pts, pose)
        else:
            return pose
        return refined if math.hypot(refined[0] - pose[0], refined[1] - pose[1]) < 2 * p.resolution else pose

    def _local(self) -> _LocalMap:
        """The local map (:meth:`_local_keyframes` at their current poses) as the matchers'
        likelihood maps: built once per keyframe and graph update, shared by the scans'
        tracking and the next keyframe's match."""
        key = (len(self.keyframes), self._graph_version)
        if self._local_map is None or self._local_map.key != key:
            p = self.params
            local = self._local_keyframes()
            ref, weights = self._points_of(local), self._weights_of(local)
            fine = (
                LikelihoodMap.from_density(ref, p.refine_resolution, p.refine_sigma, levels=0, weights=weights)
                if p.refine == "gauss_newton"
                else None
            )
            self._local_map = _LocalMap(key, ref, LikelihoodMap.from_points(ref, p.resolution, p.match_sigma), fine)
        return self._local_map

    def _pair_matches(self, k: int, pts: np.ndarray, matched) -> list[tuple[int, tuple]]:
        """Keyframe k (at ``matched``) refined against each of the ``pair_edges`` keyframes
        before it alone: [(i, relative pose from i to k)]."""
        p = self.params
        return self._matches_against(range(k - 1, max(-1, k - 1 - p.pair_edges), -1), pts, matched)

    def _near_matches(self, k: int, pts: np.ndarray, matched) -> list[tuple[int, tuple]]:
        """Keyframe k matched alone against the ``near_links`` keyframes of the local
        stretch nearest to it (within ``near_link_radius``), beyond its pair links: the
        robot turning on the spot or coming back over its tracks links to where it stood
        before on a short baseline, instead of through a chain of links whose heading
        noise adds up."""
        p = self.params
        if not p.near_links:
            return []
        first = self._local_keyframes()[0]
        cand = np.arange(first, max(first, k - p.pair_edges))
        if len(cand) == 0:
            return []
        poses = self.graph.poses[cand]
        dist = np.hypot(poses[:, 0] - matched[0], poses[:, 1] - matched[1])
        near = cand[dist < p.near_link_radius]
        near = near[np.argsort(dist[dist < p.near_link_radius])][: p.near_links]
        return self._matches_against([int(i) for i in near], pts, matched)

    def _matches_against(self, indices, pts: np.ndarray, matched) -> list[tuple[int, tuple]]:
        p = self.params
        out = []
        for i in indices:
            kf = self.keyframes[i]
            if len(kf.points) < 20:
                continue
            z0 = relative(self.graph.pose(i), matched)
            if p.pair_match == "icp_visible":
                z = self._icp_visible(i, pts, z0)
            else:
                if kf.density is None:
                    ref, w = self._pair_reference(i)
                    kf.density = LikelihoodMap.from_density(
                        ref, p.refine_resolution, p.refine_sigma, levels=0, weights=w
                    )
                z = refine(kf.density, pts, z0)[0]
            if math.hypot(z[0] - z0[0], z[1] - z0[1]) < 2 * p.resolution:
                out.append((i, z))
        return out

    def _icp_visible(self, i: int, pts: np.ndarray, z0) -> tuple:
        """Keyframe i -> the new keyframe by ICP, on the new returns keyframe i could have
        seen (at the prior, then again at the first match): a return on a surface the
        reference never saw (round a corner, past furniture) would be pulled onto what it
        did see, which lies back towards it."""
        kf = self.keyframes[i]
        if kf.pair_icp is None:
            kf.pair_icp = IcpReference(self._pair_reference(i)[0], neighbours=10)
        return self._align_visible(kf.pair_icp, kf.scans[0][1], pts, z0)

    def _align_visible(self, reference: IcpReference, scan: _Scan, pts: np.ndarray, z0) -> tuple:
        """``pts`` aligned on ``reference`` by ICP from ``z0``, on those that ``scan`` (the
        reference's laser) could have seen; ``z0`` when fewer than 20."""
        z = z0
        for _ in range(2):
            keep = _seen_from(scan, transform(z, pts), self.params.sensor_offset, self.params.range_noise)
            if keep.sum() < 20:
                return z0
            z = reference.align(pts[keep], z, iterations=30)[0]
        return z

    def _pair_reference(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Keyframe i's returns as a pair link's reference, in its base frame, and their
        weights: with ``pair_all_scans`` those of all its scans, else its first scan's.

        The odometry places the later scans, its heading corrected by the graph's: the
        heading error from keyframe i to i + 1 (a drift) is taken off each scan in
        proportion to the time elapsed. Raw, a drift of 0.5 deg/s (wheel odometry without a
        gyro) smears the reference and pulls every link its way. The odometry's distance
        is kept: the matches' own is the one that shrinks."""
        p = self.params
        kf = self.keyframes[i]
        if not p.pair_all_scans or len(kf.scans) < 2 or i + 1 >= len(self.keyframes):
            return kf.points, kf.weights
        nxt = self.keyframes[i + 1]
        err = relative(relative(kf.odom, nxt.odom), relative(self.graph.pose(i), self.graph.pose(i + 1)))
        span = max(nxt.t - kf.t, 1e-9)
        parts = []
        for delta, scan in kf.scans:
            if abs(delta[2]) > p.pair_scan_turn:
                continue
            f = min(max((scan.t - kf.t) / span, 0.0), 1.0)
            at = (delta[0], delta[1], delta[2] + f * err[2])
            parts.append(transform(at, match_points(scan, p.match_max_range, p.sensor_offset)))
        pts = np.vstack(parts)
        return pts, self._weights(pts)

    def _local_keyframes(self) -> list[int]:
        """The keyframes of the local map: those less than ``loop_min_travel`` back along
        the path (older ones come in only through a loop closure), at most
        ``local_keyframes`` of them, spread evenly over that stretch. Counting travel, not
        keyframes, keeps the stretch's oldest keyframes in the map while the robot turns on
        the spot or dithers: matched only against its own last few keyframes, it would
        drift with them."""
        p = self.params
        n = len(self.keyframes)
        travel = np.fromiter((kf.travel for kf in self.keyframes), float, n)
        first = int(np.searchsorted(travel, self._travel - p.loop_min_travel, side="right"))
        first = min(first, max(0, n - 2))  # at least the last two
        if n - first <= p.local_keyframes:
            return list(range(first, n))
        picks = np.unique(np.round(np.linspace(first, n - 1, p.local_keyframes)).astype(int))
        return [int(i) for i in picks]

    def _refine(self, ref: np.ndarray, pts: np.ndarray, pose, weights=None) -> tuple:
        """The lattice pose refined by the configured method."""
        p = self.params
        if p.refine == "gauss_newton":
            fine = LikelihoodMap.from_density(ref, p.refine_resolution, p.refine_sigma, levels=0, weights=weights)
            return refine(fine, pts, pose)[0]
        if p.refine == "icp":
            refined, _, inliers = icp(ref, pts, pose)
            return refined if inliers > 0.5 else pose
        return pose

    def _odom_information(self, z) -> np.ndarray:
        p = self.params
        d, turn = math.hypot(z[0], z[1]), abs(z[2])
        sx = max(p.odom_floor[0], p.odom_xy_per_m * d)
        sy = max(p.odom_floor[1], p.odom_xy_per_m * d)
        st = max(p.odom_floor[2], p.odom_yaw_per_m * d + p.odom_yaw_per_rad * turn)
        return np.diag([1 / sx**2, 1 / sy**2, 1 / st**2])

    # -- loop closure --------------------------------------------------------------------------
    def _close_loop(self, k: int) -> bool:
        """Try to match keyframe k against old keyframes near it; on success add the edge,
        optimise the graph and mark the map for a rebuild."""
        p = self.params
        kf = self.keyframes[k]
        here = self.graph.pose(k)
        poses = self.graph.poses
        travel = np.array([f.travel for f in self.keyframes])
        old = np.nonzero(kf.travel - travel >= p.loop_min_travel)[0]
        if len(old) == 0:
            return False
        dist = np.hypot(poses[old, 0] - here[0], poses[old, 1] - here[1])
        near = old[dist <= p.loop_radius]
        if len(near) == 0:
            return False
        order = near[np.argsort(np.hypot(poses[near, 0] - here[0], poses[near, 1] - here[1]))]
        tried: list[int] = []
        for j in order:
            if len(tried) >= p.loop_candidates:
                break
            if any(abs(int(j) - i) <= p.loop_submap for i in tried):
                continue  # the same submap again
            tried.append(int(j))
            lo, hi = max(0, j - p.loop_submap), min(len(self.keyframes), j + p.loop_submap + 1)
            hi = min(hi, int(np.searchsorted(travel, kf.travel - p.loop_min_travel, side="right")))
            ref, weights = self._points_of(range(lo, hi)), self._weights_of(range(lo, hi))
            if len(ref) < 50:
                continue
            lmap = LikelihoodMap.from_points(ref, p.resolution, p.match_sigma, margin=p.loop_window_xy + 1.0)
            res = self.matcher.match(lmap, kf.points, here, p.loop_window_xy, p.loop_window_yaw)
            if res.score < p.loop_min_score:
                continue
            pose = self._refine(ref, kf.points, res.pose, weights)
            if math.hypot(pose[0] - res.pose[0], pose[1] - res.pose[1]) > p.loop_max_refine_shift:
                continue
            if not self._plausible_correction(here, pose, kf.travel - travel[j]):
                continue
            self.graph.add_edge(
                int(j),
                k,
                relative(self.graph.pose(int(j)), pose),
                _information(p.loop_cov_scale * res.covariance),
                "loop",
            )
            self.graph.optimize(loss="cauchy", f_scale=3.0)
            self._graph_version += 1
            self.loop_closures += 1
            self._dirty = self._dirty or self._map_moved()
            return True
        return False

    def _plausible_correction(self, here, pose, travelled: float) -> bool:
        """Whether moving the keyframe from ``here`` to ``pose`` is a drift the front end
        could have made over ``travelled`` metres. A house repeats itself (parallel walls,
        door after door): a match that would move the robot further than that has found
        the wrong wall, however good its score."""
        p = self.params
        shift = relative(here, pose)
        return (
            math.hypot(shift[0], shift[1]) <= p.loop_gate_xy[0] + p.loop_gate_xy[1] * travelled
            and abs(shift[2]) <= p.loop_gate_yaw[0] + p.loop_gate_yaw[1] * travelled
        )

    def _map_moved(self) -> bool:
        """Whether some keyframe now stands more than ``rebuild_shift`` from where its scans
        went into the grid (its yaw counted at ``match_max_range``'s lever arm). A closure
        in a place mapped well moves little; rebuilding the grid after each one would cost
        seconds for nothing."""
        p = self.params
        now = self.graph.poses
        then = np.asarray(self._integrated_at, dtype=np.float64)
        dyaw = np.abs(np.remainder(now[:, 2] - then[:, 2] + math.pi, 2 * math.pi) - math.pi)
        shift = np.hypot(now[:, 0] - then[:, 0], now[:, 1] - then[:, 1]) + dyaw * p.match_max_range
        return bool(shift.max() > p.rebuild_shift)

    # -- helpers -------------------------------------------------------------------------------
    def _points_of(self, indices) -> np.ndarray:
        """The keyframes' returns in the map frame, at their current poses."""
        parts = [transform(self.graph.pose(i), self.keyframes[i].points) for i in indices]
        return np.vstack(parts) if parts else np.zeros((0, 2))

    def _range_sigma(self, pts: np.ndarray) -> np.ndarray:
        """Base-frame returns' range noise [m] (SlamParams.range_noise)."""
        p = self.params
        sensor_xy = np.asarray(p.sensor_offset[:2], dtype=np.float64)
        return np.maximum(p.range_noise[0], p.range_noise[1] * np.hypot(*(pts - sensor_xy).T))

    def _weights(self, pts: np.ndarray) -> np.ndarray:
        """Base-frame returns' weights in a match: 1 / range noise^2, relative to the nearest's."""
        return (self.params.range_noise[0] / self._range_sigma(pts)) ** 2

    def _weights_of(self, indices) -> np.ndarray:
        parts = [self.keyframes[i].weights for i in indices]
        return np.concatenate(parts) if parts else np.zeros(0)

    def _integrate(self, base_pose, scan: _Scan) -> None:
        if self._dirty:
            return  # rebuilt from scratch on the next map()
        sensor = compose(base_pose, self.params.sensor_offset)
        self.grid.integrate(sensor, scan.ranges, scan.angles, scan.range_max, scan.range_min)


def match_points(scan: _Scan, max_range: float, sensor_offset) -> np.ndarray:
    """The returns used for matching, as base-frame points: those nearer than ``max_range``
    [m] by their neighbours' ranges. A cut on a return's own range would keep, of a wall
    just beyond it, the returns whose noise made them short and so pull the wall (and the
    robot's pose) towards the laser; the median of the two beams either side carries no
    information about this beam's noise, so the kept returns stay unbiased. (The beams
    are taken as a ring, as a 360-degree scan's are.)"""
    r = np.asarray(scan.ranges, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(r) & (r >= scan.range_min) & (r < scan.range_max)
    near = np.where(valid, r, np.nan)
    sides = np.stack([np.roll(near, d) for d in (-2, -1, 1, 2)])
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all four neighbours without a return
        typical = np.nanmedian(sides, axis=0)
    keep = valid & (typical < max_range)
    return scan_points(np.where(keep, r, np.inf), scan.angles, scan.range_max, scan.range_min, sensor_offset)


def _seen_from(scan: _Scan, q: np.ndarray, sensor_offset, range_noise, k_sigma: float = 3.0) -> np.ndarray:
    """Which points q (the scan's base frame) the scan's laser could have seen: its beam at
    their bearing, or a neighbour, reaches at least to their range less k sigma of both
    ranges' noise."""
    d = q - np.asarray(sensor_offset[:2])
    rho, bear = np.hypot(d[:, 0], d[:, 1]), np.arctan2(d[:, 1], d[:, 0]) - sensor_offset[2]
    inc = scan.angles[1] - scan.angles[0]
    idx = np.round((bear - scan.angles[0]) / inc).astype(int) % len(scan.angles)
    r = np.where(np.isfinite(scan.ranges), scan.ranges, np.inf).astype(float)
    reach = np.maximum(np.maximum(r, np.roll(r, 1)), np.roll(r, -1))[idx]
    sigma = math.sqrt(2) * np.maximum(range_noise[0], range_noise[1] * rho)
    return rho <= reach + k_sigma * sigma


def _information(cov: np.ndarray) -> np.ndarray:
    """The inverse of a covariance, symmetrised."""
    info = np.linalg.inv(np.asarray(cov, dtype=np.float64))
    return 0.5 * (info + info.T)
