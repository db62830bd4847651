"""Collision-free arm motion in joint space: a straight line when it is free, else OMPL.

The pipeline of :func:`plan_joint_motion`, MoveIt-style:

1. check the inputs; clip a start that is a hair outside the joint limits
   (encoder noise), reject one in collision;
2. try the straight joint-space segment (checked every ``resolution`` rad);
3. otherwise plan with an OMPL geometric planner (RRTConnect by default) in
   the joint space, with the scene as the state validity checker;
4. simplify: OMPL's vertex reduction, then a greedy shortcut that keeps the
   fewest waypoints whose straight segments are all valid;
5. re-check the final path densely (every ``recheck_resolution`` rad, max-norm).

Planning never raises for an unsolvable query: the :class:`MotionPlan` says
why it failed. Planning time is wall-clock (the query runs inline).

OMPL's random numbers are seeded once per process with :func:`seed_planners`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from .errors import InvalidInputError
from .failure import FailureReason
from .kinematics import ArmPose, JointValues
from .scene import PlanningScene

__all__ = ["MotionPlan", "PLANNERS", "plan_joint_motion", "plan_pose_motion", "path_length", "seed_planners"]

ou.setLogLevel(ou.LOG_WARN)

#: OMPL geometric planners that can be named in ``planner=``.
PLANNERS = (
    "RRTConnect",
    "RRT",
    "RRTstar",
    "InformedRRTstar",
    "PRM",
    "PRMstar",
    "KPIECE1",
    "BKPIECE1",
    "LBKPIECE1",
    "BITstar",
    "FMT",
    "BFMT",
)
STRAIGHT = "straight"
_START_CLIP = 0.05  # a start this far outside a limit [rad] is clipped onto it


@dataclass(frozen=True)
class MotionPlan:
    """Result of an arm planning query.

    Attributes:
        path: joint waypoints [rad], start first, goal last; each consecutive
            pair is a straight joint-space segment that passed the dense
            re-check. Empty when the query failed.
        planner: ``"straight"`` when the direct segment was free, else the
            OMPL planner's name.
        planning_time: wall-clock time of the whole query [s].
        length_raw: joint-space length of the path before simplification [rad]
            (Euclidean norm over the joints, summed over segments).
        length: the same after simplification [rad].
        failure: None on success, else why it failed.
        message: the failure in words ("" on success).
        start: the start used [rad] (after clipping into the limits).
        goal: the goal reached [rad] (for a pose query: the IK solution chosen);
            empty on failure.
    """

    path: tuple[tuple[float, ...], ...]
    planner: str
    planning_time: float
    length_raw: float
    length: float
    failure: FailureReason | None = None
    message: str = ""
    start: tuple[float, ...] = ()
    goal: tuple[float, ...] = ()
    raw_waypoints: int = field(default=0, repr=False)

    @property
    def ok(self) -> bool:
        """True when ``path`` is a valid collision-free path."""
        return self.failure is None

    def raise_for_failure(self) -> None:
        """Raise the :class:`~planning.errors.PlanningError` subclass for ``failure``."""
        if self.failure is not None:
            raise self.failure.error_type(self.message)


def seed_planners(seed: int) -> None:
    """Seed OMPL's random numbers. Call once, before the first plan, for
    repeatable plans; OMPL ignores a seed set after it started sampling."""
    ou.RNG.setSeed(int(seed))


def path_length(path: Sequence[JointValues]) -> float:
    """Joint-space length of a polyline [rad]: sum of the segments' Euclidean norms."""
    pts = np.asarray(path, dtype=float)
    if len(pts) < 2:
        return 0.0
    return float(np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)))


def _as_q(q: Sequence[float], what: str) -> np.ndarray:
    arr = np.asarray(q, dtype=float)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{what} must be 4 finite joint positions [rad], got {q!r}")
    return arr


def _fail(
    t0: float, reason: FailureReason, message: str, planner: str = "", start: np.ndarray | None = None
) -> MotionPlan:
    return MotionPlan(
        path=(),
        planner=planner,
        planning_time=time.perf_counter() - t0,
        length_raw=math.nan,
        length=math.nan,
        failure=reason,
        message=message,
        start=tuple(float(v) for v in start) if start is not None else (),
    )


def _tuple_path(path: list[np.ndarray]) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in p) for p in path)


SegmentCheck = Callable[[np.ndarray, np.ndarray], bool]


def _greedy_shortcut(path: list[np.ndarray], valid: SegmentCheck) -> list[np.ndarray]:
    """Fewest waypoints: from each kept point jump to the farthest one in sight."""
    out = [path[0]]
    i = 0
    while i < len(path) - 1:
        j = len(path) - 1
        while j > i + 1 and not valid(path[i], path[j]):
            j -= 1
        out.append(path[j])
        i = j
    return out


def _point_at(path: list[np.ndarray], cum: np.ndarray, t: float) -> tuple[int, np.ndarray]:
    """Segment index and point at arc length ``t`` along a polyline."""
    i = int(np.searchsorted(cum, t, side="right") - 1)
    i = min(max(i, 0), len(path) - 2)
    seg = cum[i + 1] - cum[i]
    u = 0.0 if seg <= 0 else (t - cum[i]) / seg
    return i, path[i] + (path[i + 1] - path[i]) * u


def _random_shortcut(
    path: list[np.ndarray],
    valid: SegmentCheck,
    rng: np.random.Generator,
    attempts: int,
    deadline: float,
    patience: int = 10,
) -> list[np.ndarray]:
    """OMPL-style shortcutting: join two random points of the path by a straight
    segment whenever that segment is valid; stop after ``patience`` misses in a row."""
    misses = 0
    for _ in range(attempts):
        if len(path) < 3 or misses >= patience or time.perf_counter() > deadline:
            break
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        t1, t2 = np.sort(rng.uniform(0.0, cum[-1], 2))
        i1, p1 = _point_at(path, cum, t1)
        i2, p2 = _point_at(path, cum, t2)
        if i1 == i2:
            misses += 1
            continue
        if valid(p1, p2):
            path = path[: i1 + 1] + [p1, p2] + path[i2 + 1 :]
            path = [p for j, p in enumerate(path) if j == 0 or np.max(np.abs(p - path[j - 1])) > 1e-9]
            misses = 0
        else:
            misses += 1
    return path


def _simplify(reduced: list[np.ndarray], valid: SegmentCheck, attempts: int, deadline: float) -> list[np.ndarray]:
    path = _greedy_shortcut(reduced, valid)
    path = _random_shortcut(path, valid, np.random.default_rng(0), attempts, deadline)
    return _greedy_shortcut(path, valid)


def _plan(
    start: np.ndarray,
    goals: list[np.ndarray],
    scene: PlanningScene,
    *,
    planner: str,
    timeout: float,
    resolution: float,
    recheck_resolution: float,
    simplify: bool,
    try_straight: bool,
    t0: float,
    simplify_time: float = 0.05,
    shortcut_attempts: int = 30,
) -> MotionPlan:
    k = scene.kinematics
    # 2. straight segments, nearest goal first
    if try_straight:
        for goal in goals:
            if scene.segment_valid(start, goal, recheck_resolution):
                path = [start, goal]
                length = path_length(path)
                return MotionPlan(
                    path=_tuple_path(path),
                    planner=STRAIGHT,
                    planning_time=time.perf_counter() - t0,
                    length_raw=length,
                    length=length,
                    start=tuple(float(v) for v in start),
                    goal=tuple(float(v) for v in goal),
                    raw_waypoints=2,
                )

    # 3. OMPL in joint space
    space = ob.RealVectorStateSpace(4)
    bounds = ob.RealVectorBounds(4)
    for i in range(4):
        bounds.setLow(i, float(k.lower[i]))
        bounds.setHigh(i, float(k.upper[i]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    is_valid = scene.is_valid

    def valid(state: ob.State) -> bool:
        return is_valid((state[0], state[1], state[2], state[3]))

    ss.setStateValidityChecker(valid)
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(resolution / si.getMaximumExtent())
    s = space.allocState()
    s[0:4] = [float(v) for v in start]
    ss.setStartState(s)
    goal_region = ob.GoalStates(si)
    for goal in goals:
        g = space.allocState()
        g[0:4] = [float(v) for v in goal]
        goal_region.addState(g)
    ss.setGoal(goal_region)
    ss.setPlanner(getattr(og, planner)(si))
    remaining = timeout - (time.perf_counter() - t0)
    if remaining <= 0:
        return _fail(
            t0,
            FailureReason.TIMEOUT,
            f"no time left for {planner} after the checks ({timeout} s budget)",
            planner,
            start,
        )
    status = ss.solve(remaining)
    if not ss.haveExactSolutionPath():
        text = status.asString()
        timed_out = "timeout" in text.lower() or "approximate" in text.lower()
        reason = FailureReason.TIMEOUT if timed_out else FailureReason.NO_PATH
        return _fail(
            t0,
            reason,
            f"{planner} found no collision-free path in {remaining:.3f} s ({text}) "
            f"from {np.round(start, 3).tolist()} to {len(goals)} goal state(s)",
            planner,
            start,
        )
    solution = ss.getSolutionPath()
    raw = [np.array([st[0], st[1], st[2], st[3]]) for st in solution.getStates()]
    length_raw = path_length(raw)

    # 4. simplification. Shortcuts are checked at twice the re-check step (as
    # OMPL's own simplifier uses its coarser motion checks), the result densely.
    def fine(a: np.ndarray, b: np.ndarray) -> bool:
        return scene.segment_valid(a, b, recheck_resolution)

    def coarse(a: np.ndarray, b: np.ndarray) -> bool:
        return scene.segment_valid(a, b, 2 * recheck_resolution, max_step=2 * scene.max_step)

    def dense_ok(p: list[np.ndarray]) -> bool:
        return all(fine(a, b) for a, b in zip(p[:-1], p[1:]))

    candidates: list[Callable[[], list[np.ndarray]]] = []
    if simplify and len(raw) > 2:
        simplifier = og.PathSimplifier(si)
        simplifier.reduceVertices(solution)
        reduced = [np.array([st[0], st[1], st[2], st[3]]) for st in solution.getStates()]
        deadline = time.perf_counter() + max(0.0, min(simplify_time, timeout - (time.perf_counter() - t0)))
        candidates.append(lambda: _simplify(reduced, coarse, shortcut_attempts, deadline))
        candidates.append(lambda: _simplify(reduced, fine, shortcut_attempts, deadline))
    candidates.append(lambda: raw)

    # 5. dense re-check of the final path; fall back to a more careful candidate
    for make in candidates:
        path = make()
        if dense_ok(path):
            break
    else:
        return _fail(
            t0,
            FailureReason.RECHECK_FAILED,
            f"{planner} returned a path that collides when re-checked every {recheck_resolution} rad",
            planner,
            start,
        )
    return MotionPlan(
        path=_tuple_path(path),
        planner=planner,
        planning_time=time.perf_counter() - t0,
        length_raw=length_raw,
        length=path_length(path),
        start=tuple(float(v) for v in start),
        goal=tuple(float(v) for v in path[-1]),
        raw_waypoints=len(raw),
    )


def _prepare_start(start: Sequence[float], scene: PlanningScene, t0: float) -> np.ndarray | MotionPlan:
    k = scene.kinematics
    try:
        q = _as_q(start, "start")
    except InvalidInputError as exc:
        return _fail(t0, FailureReason.INVALID_INPUT, str(exc))
    below, above = q < k.lower - _START_CLIP, q > k.upper + _START_CLIP
    if np.any(below | above):
        bad = [k.joint_names[i] for i in np.flatnonzero(below | above)]
        return _fail(
            t0, FailureReason.START_INVALID, f"start {np.round(q, 4).tolist()} is outside the limits of {bad}", start=q
        )
    q = np.clip(q, k.lower, k.upper)
    report = scene.check(q)
    if not report.valid:
        return _fail(
            t0, FailureReason.START_INVALID, f"start {np.round(q, 4).tolist()} is invalid: {report.describe()}", start=q
        )
    return q


def _check_options(planner: str, timeout: float, resolution: float, recheck_resolution: float) -> str | None:
    if planner not in PLANNERS:
        return f"unknown planner {planner!r}; choices: {', '.join(PLANNERS)}"
    if not (math.isfinite(timeout) and timeout > 0):
        return f"timeout must be > 0 s, got {timeout!r}"
    for name, v in (("resolution", resolution), ("recheck_resolution", recheck_resolution)):
        if not (math.isfinite(v) and 0 < v <= 0.5):
            return f"{name} must be in (0, 0.5] rad, got {v!r}"
    return None


def plan_joint_motion(
    start: Sequence[float],
    goal: Sequence[float],
    scene: PlanningScene,
    *,
    planner: str = "RRTConnect",
    timeout: float = 1.0,
    resolution: float = 0.02,
    recheck_resolution: float = 0.01,
    simplify: bool = True,
    try_straight: bool = True,
) -> MotionPlan:
    """Plan a collision-free joint-space path from ``start`` to ``goal`` [rad].

    Args:
        start, goal: joint positions (joint1..joint4) [rad].
        scene: the planning scene (validity checker).
        planner: an OMPL geometric planner from :data:`PLANNERS`.
        timeout: time budget for the whole query [s] (wall clock).
        resolution: step of OMPL's motion checks [rad] (Euclidean).
        recheck_resolution: step of the straight-line test, the shortcut checks
            and the final re-check [rad] (largest joint step).
        simplify: shorten the OMPL path.
        try_straight: return the direct segment when it is valid.

    Returns:
        A :class:`MotionPlan`; it does not raise for invalid or unsolvable queries.
    """
    t0 = time.perf_counter()
    problem = _check_options(planner, timeout, resolution, recheck_resolution)
    if problem:
        return _fail(t0, FailureReason.INVALID_INPUT, problem, planner)
    q0 = _prepare_start(start, scene, t0)
    if isinstance(q0, MotionPlan):
        return q0
    try:
        qg = _as_q(goal, "goal")
    except InvalidInputError as exc:
        return _fail(t0, FailureReason.INVALID_INPUT, str(exc), planner, q0)
    report = scene.check(qg)
    if not report.valid:
        return _fail(
            t0,
            FailureReason.GOAL_INVALID,
            f"goal {np.round(qg, 4).tolist()} is invalid: {report.describe()}",
            planner,
            q0,
        )
    return _plan(
        q0,
        [qg],
        scene,
        planner=planner,
        timeout=timeout,
        resolution=resolution,
        recheck_resolution=recheck_resolution,
        simplify=simplify,
        try_straight=try_straight,
        t0=t0,
    )


def plan_pose_motion(
    start: Sequence[float],
    pose: ArmPose | Sequence[float],
    scene: PlanningScene,
    *,
    heading: Literal["outward", "inward", "any"] = "outward",
    planner: str = "RRTConnect",
    timeout: float = 1.0,
    resolution: float = 0.02,
    recheck_resolution: float = 0.01,
    simplify: bool = True,
    try_straight: bool = True,
) -> MotionPlan:
    """Plan from joints ``start`` [rad] to a tool pose ``(x, y, z [m], pitch [rad])``.

    The pose is in the scene model's root frame (``base_footprint``). Every
    collision-free IK solution is a goal: the straight segment to each is tried
    nearest first, then OMPL plans to the set of them at once.

    Other arguments are those of :func:`plan_joint_motion`; ``heading`` is that
    of :meth:`ArmKinematics.ik`.
    """
    t0 = time.perf_counter()
    problem = _check_options(planner, timeout, resolution, recheck_resolution)
    if problem:
        return _fail(t0, FailureReason.INVALID_INPUT, problem, planner)
    q0 = _prepare_start(start, scene, t0)
    if isinstance(q0, MotionPlan):
        return q0
    if not isinstance(pose, ArmPose):
        try:
            x, y, z, pitch = (float(v) for v in pose)
        except (TypeError, ValueError):
            return _fail(t0, FailureReason.INVALID_INPUT, f"pose must be (x, y, z, pitch), got {pose!r}", planner, q0)
        pose = ArmPose(x, y, z, pitch)
    ik = scene.kinematics.ik(pose.x, pose.y, pose.z, pose.pitch, seed=q0, heading=heading)
    if not ik.ok:
        return _fail(t0, ik.failure or FailureReason.UNREACHABLE, ik.message, planner, q0)
    goals, problems = [], []
    for sol in ik.solutions:
        report = scene.check(sol.q)
        if report.valid:
            goals.append(np.asarray(sol.q))
        else:
            problems.append(f"elbow {sol.elbow}: {report.describe()}")
    if not goals:
        return _fail(
            t0,
            FailureReason.GOAL_INVALID,
            f"every IK solution for {pose} is in collision: " + "; ".join(problems),
            planner,
            q0,
        )
    return _plan(
        q0,
        goals,
        scene,
        planner=planner,
        timeout=timeout,
        resolution=resolution,
        recheck_resolution=recheck_resolution,
        simplify=simplify,
        try_straight=try_straight,
        t0=t0,
    )
