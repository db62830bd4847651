"""The localiser's logic, as AMCL's node has it, without any transport.

:class:`Amcl` takes odometry poses and laser scans (plain numbers; :class:`Scan` reads a
``sensor_msgs/LaserScan``) and keeps a :class:`~navstack.particle_filter.ParticleFilter`:

* a filter update (motion, measurement, resampling) runs on a scan when the odometry has
  moved more than ``update_min_d`` or turned more than ``update_min_a`` since the last
  one, and on the first scan after (re)initialisation;
* between updates the pose follows the odometry: ``pose(odom)`` is ``map_to_odom``
  composed with any odometry pose, so it is available at the odometry's rate;
* every scan (moving or not) is scored against the map at the current estimate: the
  share of beams ending within ``inlier_dist`` of an obstacle, smoothed. When that score
  stays below ``lost_score``, or below ``lost_drop`` times its slow baseline (its average
  while localised: a sudden drop, as augmented MCL's w_fast / w_slow), for ``lost_scans``
  scans, the robot is declared lost (it was kidnapped, or the estimate diverged) and, with
  ``auto_recover``, the filter is relocalised globally from the current scan (or uniformly,
  ``recovery="uniform"``), keeping ``keep_share`` of its particles so that a false alarm
  is undone by the next measurement update;
* while such a relocalisation runs, ``map_to_odom`` (what is published) holds the last
  localised transform and follows the odometry: the filter's estimate is adopted once it
  has converged again. A false alarm (an arm or an object in front of the laser at a table)
  then costs nothing, where the estimate of a half-done relocalisation used to jump to a
  look-alike place metres away for a few seconds. The health check scores the filter's
  own estimate (``filter_map_to_odom``), so a real kidnap still converges and is adopted.
  A converged pose farther than ``adopt_near`` from the held one is adopted only if the
  scan fits it ``adopt_margin`` better: from a standstill by an unmapped object, one
  scan's search may settle on a look-alike place metres away that fits no better;
* a global localisation with no pose known (none given, none converged to yet) is declared
  localised only where the scan fits no other place within ``unique_margin`` as well, and
  from its pose refined on all the beams (:meth:`Amcl._confirm_unique`): in a symmetric
  room it stays uncertain (``ambiguous``) rather than pick a look-alike pose.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .likelihood_field import LaserModelParams, beam_endpoints_laser_frame
from .map_io import OccupancyMap
from .odometry import Pose, as_pose
from .particle_filter import Estimate, FilterParams, ParticleFilter, wrap1

# states
UNINITIALISED = "uninitialised"
LOCALISED = "localised"
UNCERTAIN = "uncertain"  # initialised or relocalising, not converged yet
LOST = "lost"  # the scan no longer fits the map at the estimate

# the spread the filter starts again with round a held pose it keeps (5 cm, 3 degrees)
KEPT_POSE_COV = np.diag([0.05**2, 0.05**2, math.radians(3) ** 2])


@dataclass
class Scan:
    """A planar laser scan (sensor_msgs/LaserScan's fields that matter)."""

    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float

    @classmethod
    def from_msg(cls, msg) -> Scan:
        return cls(
            np.asarray(msg.ranges, dtype=np.float32), msg.angle_min, msg.angle_increment, msg.range_min, msg.range_max
        )

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))

    def valid(self) -> np.ndarray:
        r = self.ranges
        return np.isfinite(r) & (r >= self.range_min) & (r < self.range_max)


@dataclass
class AmclParams:
    update_min_d: float = 0.25  # [m]
    update_min_a: float = 0.2  # [rad]
    resample_interval: int = 1
    max_beams: int = 60
    laser_pose: tuple = (0.0, 0.0, 0.0)  # the laser in the base frame (x, y, yaw)
    # health and recovery
    inlier_dist: float = 0.15  # a beam fits when it ends this near an obstacle [m]
    score_smoothing: float = 0.4  # weight of the newest scan in the smoothed score
    baseline_smoothing: float = 0.02  # ... and in the slow baseline it is compared with
    lost_score: float = 0.45  # below this the scan does not fit
    lost_drop: float = 0.75  # ... nor below this share of the baseline
    lost_scans: int = 3  # consecutive scans like that: lost
    min_beams: int = 30  # scans with fewer valid beams are not judged
    keep_share: float = 0.25  # share of the current particles kept when lost
    ok_score: float = 0.6  # converged needs at least this ...
    converged_std_xy: float = 0.12  # ... and the heaviest cluster this tight [m]
    converged_std_yaw: float = 0.12  # [rad]
    converged_weight: float = 0.8  # ... holding this share of the weight
    relocalise_grace: float = 6.0  # after a relocalisation, [s] before lost may be declared again
    adopt_near: float = 0.5  # a relocalised pose this near the held one is adopted [m] ...
    adopt_margin: float = 0.15  # ... one farther only if the scan fits it this much better
    # a global localisation with no pose known converges only where the scan fits no other place
    unique_margin: float = 0.1  # ... as well as the estimate, less this (share of beams)
    unique_near: float = 0.5  # another place: this far from the estimate [m] ...
    unique_near_yaw: float = 0.5  # ... or turned this far from it [rad]
    unique_places: int = 6  # best places of a global search compared with it
    auto_recover: bool = True
    recovery: str = "informed"  # "informed" (scan-matched seeding) or "uniform"


@dataclass
class Status:
    state: str = UNINITIALISED
    score: float = 0.0  # smoothed share of beams that fit the map
    baseline: float = 0.0  # its slow average while localised
    std_xy: float = math.inf
    std_yaw: float = math.inf
    particles: int = 0
    clusters: int = 0
    updates: int = 0
    recoveries: int = 0  # global relocalisations started because lost
    lost_count: int = 0  # times lost was declared
    kept_count: int = 0  # relocalisations that found no better pose than the held one
    ambiguous: bool = False  # a global localisation's estimate fits no better than another place
    rival_score: float = 0.0  # ... the scan's fit at the best other place (its last check)
    last_update_ms: float = 0.0
    last_lost: float | None = None  # when lost was last declared (clock time)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def compose(a, b) -> Pose:
    """Pose a (x, y, yaw) composed with pose b expressed in a's frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap1(a[2] + b[2]))


def inverse(a) -> Pose:
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], wrap1(-a[2]))


class Amcl:
    """Adaptive Monte Carlo localisation on an occupancy map."""

    def __init__(
        self,
        occ_map: OccupancyMap,
        params: AmclParams | None = None,
        filter_params: FilterParams | None = None,
        laser: LaserModelParams | None = None,
        seed: int | None = None,
        clock=time.monotonic,
    ):
        self.params = params or AmclParams()
        self.pf = ParticleFilter(occ_map, filter_params, laser, seed)
        self.rng = self.pf.rng
        self.clock = clock
        self.status = Status()
        self.map_to_odom = (0.0, 0.0, 0.0)  # published: held while relocalising
        self.filter_map_to_odom = (0.0, 0.0, 0.0)  # the filter's own estimate
        self.holding = False  # relocalising after lost, map_to_odom held
        self._trusted = False  # map_to_odom is a pose given or converged to
        self.estimate: Estimate | None = None
        self._odom_at_update: Pose | None = None  # odometry pose at the last filter update
        self._last_odom: Pose | None = None  # the newest odometry pose
        self._force_update = False
        # share of particles to keep, while an informed global localisation waits for a scan
        self._pending_global: float | None = None
        self._low_scans = 0
        self._grace_until = -math.inf
        # the scan's best places (map -> odom), their fits, the odometry pose
        self._rivals: tuple[list[Pose], list[float], Pose] | None = None
        self.update_times: list[float] = []  # [s] per filter update
        self.search_times: list[float] = []  # [s] per scan-informed global localisation

    # -- inputs ------------------------------------------------------------------------------
    def set_map(self, occ_map: OccupancyMap) -> None:
        self.pf.set_map(occ_map)

    def on_odometry(self, odom) -> None:
        """The newest odometry pose (x, y, yaw), for :meth:`pose` between scans."""
        self._last_odom = as_pose(odom)

    def initialise(self, pose, cov, odom=None) -> None:
        """The /initialpose case: particles round ``pose`` (map frame) with 3x3 ``cov``,
        the robot being at odometry pose ``odom`` (the newest one when None)."""
        self.pf.initialise(pose, cov)
        odom = odom if odom is not None else self._last_odom
        self._restart(odom)
        self.estimate = self.pf.mean()
        pose = tuple(float(v) for v in pose)
        self.map_to_odom = self.filter_map_to_odom = compose(pose, inverse(odom)) if odom is not None else pose
        self.holding = False  # told where it is: nothing to hold
        self._trusted = True

    def global_localisation(self, informed: bool | None = None, keep_share: float = 0.0, hold: bool = False) -> None:
        """Forget the pose: uniform particles (AMCL), or seeded from the next scan's
        matches over the map (``informed``; the default follows ``params.recovery``),
        keeping ``keep_share`` of the current particles. ``hold``: keep ``map_to_odom``
        until the filter has converged (a recovery from lost; a caller who asks to
        forget the pose gets the filter's estimate as it goes)."""
        self.holding = hold
        self._trusted = self._trusted and hold
        if informed is None:
            informed = self.params.recovery == "informed"
        if informed:
            self._pending_global = keep_share  # done on the next scan, which it needs
        else:
            n_old = int(round(keep_share * self.pf.params.max_particles))
            old = (
                self.pf.particles[self.rng.choice(len(self.pf.particles), size=n_old, p=self.pf.weights)]
                if n_old and len(self.pf.particles)
                else np.zeros((0, 3))
            )
            self.pf.global_localisation()
            if len(old):
                self.pf._set(np.vstack([self.pf.particles[len(old) :], old]))
        self._restart(None)

    def request_nomotion_update(self) -> None:
        """Run a filter update on the next scan even if the robot has not moved (AMCL's
        request_nomotion_update service)."""
        self._force_update = True

    def _restart(self, odom) -> None:
        self._force_update = True
        self._odom_at_update = odom
        self._low_scans = 0
        self._rivals = None
        self.status.state = UNCERTAIN
        self.status.ambiguous = False
        self._grace_until = self.clock() + self.params.relocalise_grace

    def beams(self, scan: Scan, k: int | None = None) -> np.ndarray:
        """End points (K, 2) in the base frame of up to k valid beams, evenly spread with
        a random phase (all valid beams when k is None)."""
        valid = np.nonzero(scan.valid())[0]
        if k is not None and len(valid) > k:
            step = len(valid) / k
            pick = (self.rng.uniform(0, step) + step * np.arange(k)).astype(int)
            valid = valid[np.minimum(pick, len(valid) - 1)]
        xy = beam_endpoints_laser_frame(scan.ranges[valid], scan.angles[valid])
        lx, ly, lyaw = self.params.laser_pose
        if lx or ly or lyaw:
            c, s = math.cos(lyaw), math.sin(lyaw)
            xy = np.column_stack([lx + c * xy[:, 0] - s * xy[:, 1], ly + s * xy[:, 0] + c * xy[:, 1]])
        return xy.astype(np.float32)

    def on_scan(self, scan: Scan, odom, gyro: bool = False) -> bool:
        """A scan taken at odometry pose ``odom`` (x, y, yaw); ``gyro``: its heading is a
        gyro's (:meth:`ParticleFilter.predict`). Returns True when the filter updated. Does
        nothing before initialise/global_localisation."""
        if self.status.state == UNINITIALISED and self._pending_global is None:
            return False
        odom = tuple(float(v) for v in odom)
        self._last_odom = odom
        updated = False
        if self._pending_global is not None:
            t0 = time.perf_counter()
            self.pf.global_localisation_informed(self.beams(scan, None), scan.range_max, self._pending_global)
            self._pending_global = None
            self._restart(odom)
            self.search_times.append(time.perf_counter() - t0)
        if self._odom_at_update is None:
            self._odom_at_update = odom
            self._force_update = True
        old = self._odom_at_update
        moved = (
            math.hypot(odom[0] - old[0], odom[1] - old[1]) > self.params.update_min_d
            or abs(wrap1(odom[2] - old[2])) > self.params.update_min_a
        )
        if moved or self._force_update:
            t0 = time.perf_counter()
            self.pf.predict(old, odom, gyro)
            self.pf.update(self.beams(scan, self.params.max_beams), scan.range_max)
            self.status.updates += 1
            self.estimate = est = self.pf.estimate()
            if self.status.updates % self.params.resample_interval == 0:
                self.pf.resample()
            self.filter_map_to_odom = compose(tuple(est.pose), inverse(odom))
            if not self.holding:
                self.map_to_odom = self.filter_map_to_odom
            self._odom_at_update = odom
            self._force_update = False
            dt = time.perf_counter() - t0
            self.update_times.append(dt)
            self.status.last_update_ms = dt * 1000
            updated = True
        self._check_health(scan, odom)
        return updated

    # -- outputs -------------------------------------------------------------------------------
    def pose(self, odom=None):
        """The base pose (x, y, yaw) in the map frame at odometry pose ``odom`` (the
        newest one when None)."""
        if odom is None:
            odom = self._last_odom or self._odom_at_update or (0.0, 0.0, 0.0)
        return compose(self.map_to_odom, tuple(odom))

    def covariance(self) -> np.ndarray:
        return self.estimate.cov if self.estimate is not None else np.diag([1e3, 1e3, 1e3])

    def match_score(self, scan: Scan, pose) -> float:
        """The share of valid beams ending within inlier_dist of an obstacle, seen from
        ``pose`` (map frame)."""
        xy = self.beams(scan, None)
        if len(xy) == 0:
            return 0.0
        d = self.pf.field.beam_distances(np.asarray([pose], float), xy)[0]
        return float(np.mean(d < self.params.inlier_dist))

    # -- health ----------------------------------------------------------------------------------
    def _check_health(self, scan: Scan, odom) -> None:
        p, st = self.params, self.status
        st.particles = len(self.pf.particles)
        if np.count_nonzero(scan.valid()) < p.min_beams:
            return  # too little to judge by (a blocked or empty view)
        score = self.match_score(scan, compose(self.filter_map_to_odom, tuple(odom)))
        a = p.score_smoothing
        st.score = score if st.updates <= 1 and st.score == 0 else (1 - a) * st.score + a * score
        if st.state == LOCALISED:
            b = p.baseline_smoothing
            st.baseline = st.score if st.baseline == 0 else (1 - b) * st.baseline + b * st.score
        est = self.estimate
        if est is not None:
            st.std_xy, st.std_yaw, st.clusters = est.std_xy, est.std_yaw, est.clusters
        now = self.clock()
        low = st.score < p.lost_score or st.score < p.lost_drop * st.baseline
        self._low_scans = self._low_scans + 1 if low else 0
        if self._low_scans >= p.lost_scans and now >= self._grace_until:
            # the transform of the last localised state is kept until the filter converges
            hold = self._trusted  # (the low scans before have made the state uncertain)
            st.state = LOST
            st.last_lost = now
            st.lost_count += 1
            if p.auto_recover:
                st.recoveries += 1
                self.global_localisation(informed=p.recovery == "informed", keep_share=p.keep_share, hold=hold)
            return
        if st.state in (UNCERTAIN, LOCALISED):
            converged = (
                est is not None
                and st.score >= p.ok_score
                and est.std_xy <= p.converged_std_xy
                and est.std_yaw <= p.converged_std_yaw
                and est.weight >= p.converged_weight
            )
            if converged and not self._trusted:
                self._confirm_unique(scan, odom)  # uncertain still, or restarted round the pose
                return
            st.state = LOCALISED if converged else UNCERTAIN
            self._trusted = self._trusted or converged
            if converged and self.holding:
                self._adopt_or_keep(scan, odom)

    def _confirm_unique(self, scan: Scan, odom) -> None:
        """A global localisation with no pose known has converged: believe it only if the
        scan fits no other place nearly as well, and then from its pose refined on all the
        beams. The filter's weights cannot tell: its likelihood treats the beams as
        independent, so after one update the cluster that happened to be seeded nearer its
        optimum holds nearly all the weight, and at a standstill the same view repeated
        settles any tie by chance (a symmetric room, a corridor, a view of one wall). So
        the estimate and the best places of a global search on the scan are refined alike
        and compared by the share of beams that fit: unless it beats every other place by
        ``unique_margin``, the state stays uncertain (``ambiguous``) until the robot has
        moved enough for a new view. Otherwise the filter restarts round the refined pose
        (the particles sampled the pose only as densely as they were seeded, some
        centimetres off) and is trusted, as if the pose had been given."""
        p, st = self.params, self.status
        odom = tuple(odom)
        beams = self.beams(scan, None)
        pose = tuple(self.pf.refine(compose(self.filter_map_to_odom, odom), beams, scan.range_max))
        fit = self.match_score(scan, pose)
        r = self._rivals
        if (
            r is None
            or math.hypot(odom[0] - r[2][0], odom[1] - r[2][1]) > p.update_min_d
            or abs(wrap1(odom[2] - r[2][2])) > p.update_min_a
        ):
            places = self.pf.best_places(beams, scan.range_max, p.unique_places, p.unique_near, p.unique_near_yaw)
            # kept as map -> odom, so that they follow the odometry until the view changes
            r = self._rivals = (
                [compose(tuple(q), inverse(odom)) for q in places],
                [self.match_score(scan, tuple(q)) for q in places],
                odom,
            )
        rivals = [0.0]
        for m2o, f in zip(r[0], r[1]):
            q = compose(m2o, odom)
            if (
                math.hypot(q[0] - pose[0], q[1] - pose[1]) > p.unique_near
                or abs(wrap1(q[2] - pose[2])) > p.unique_near_yaw
            ):
                rivals.append(f)
        st.rival_score = max(rivals)
        st.ambiguous = st.rival_score > fit - p.unique_margin
        if st.ambiguous:
            st.state = UNCERTAIN
            return
        self.initialise(pose, KEPT_POSE_COV, odom=odom)  # converges on the next update

    def _adopt_or_keep(self, scan: Scan, odom) -> None:
        """The relocalisation after a lost has converged: adopt its pose, unless it lies
        far from the held one and the scan fits it hardly better. Then the lost was a
        false alarm (an unmapped object or the arm before the laser spoils the fit at the
        right pose) and the search settled on a look-alike place metres away, having seen
        one scan from a standstill. The filter starts again round the held pose, and the
        baseline from the present fit, which the changed view has lowered."""
        p, st = self.params, self.status
        self.holding = False
        held = compose(self.map_to_odom, tuple(odom))
        found = compose(self.filter_map_to_odom, tuple(odom))
        if math.hypot(found[0] - held[0], found[1] - held[1]) <= p.adopt_near:
            self.map_to_odom = self.filter_map_to_odom
            return
        held_fit = self.match_score(scan, held)
        if self.match_score(scan, found) >= held_fit + p.adopt_margin:
            self.map_to_odom = self.filter_map_to_odom
            return
        self.initialise(held, KEPT_POSE_COV, odom=odom)
        st.kept_count += 1
        st.score = st.baseline = held_fit
