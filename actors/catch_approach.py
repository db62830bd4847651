"""The approach to an object: approach_object, an actor of Catcher (actors/catch.py), and
the helpers only it uses: the closer looks, the standoffs with room for the base and a
clear way in, and the drive there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from bt_engine import ActorbtError, actor

from .catch_errors import ApproachError
from .catch_geometry import (
    BASE_MARGIN,
    FINGERTIPS,
    OUTLINE_REACH,
    SAME_OBJECT,
    STANDOFF_CLEARANCE,
    ends_swapped,
    grasp_xy,
    object_yaw,
    outline_discs,
    seen_again,
    segment_distance,
    target_marks,
    target_xy,
)
from .catch_parts import CatcherParts
from .strategies import GraspPlan, Strategy

HAND_HALF_WIDTH = 0.07  # half the open hand's width, with margin [m]
CONFIRM_RANGE = (0.45, 1.2)  # [m] from this near, a close look that sees something else at
#                             the target's place (and never the category) rejects the target;
#                             nearer than the first, a lying box's faces are misread (unknown)
UNNAMED_GATE = 0.04  # [m] an object of no known category this near the target,
UNNAMED_SIZE = 0.012  # [m] and as wide and high within this, seen from near, is it
ASIDE = (math.radians(45), math.radians(-45))  # headings, relative to a lying body's axis,
#                             of the closer look at it
FINGER_THICKNESS = 0.010  # [m] of each finger, outside the opening
FINGER_SPAN = (-0.10, -0.04, 0.0, FINGERTIPS)  # [m] along the hand from the object's axis
#                             at the grasp: where the fingers pass (the last of the way in)
RAISED = 0.05  # [m] an object whose base is higher stands on a surface (a table)
LOOK_SEEN = 0.75  # the closer look at a raised object is from where the camera sees
#                             this much of its height: the camera looks down, and from the
#                             usual look distance it sees nothing of a bottle on a 0.25 m TV
#                             bench (perception found it from 1.8 m, not from 1.5 m or less)
MAX_LOOK = 2.5  # [m] the farthest look distance
RAISED_LOOK_STEPS = (0.0, -0.1, -0.2, 0.15, 0.3)  # [m] look distances tried around a
#                             raised object's (a bottle on a 0.25 m bench is recognised
#                             from 1.7 to 2.3 m)
RAISED_SQUARE = math.radians(5)  # a box on a table is grasped straight in from the look
#                             pose, with no look nearer: the hand comes in this square to
#                             one of its sides at most. Across its 70 mm side, 5 degrees off,
#                             a carton spans 74 mm of the 85 mm opening: 5 mm either side for
#                             the estimate's error (11 degrees off it spans 77 mm, and a
#                             finger runs into its corner and pushes it off the grasp)


class Approaching(CatcherParts):
    """Catcher's approach (a mixin of it: it uses Catcher's shared helpers)."""

    def _free_standoff(
        self,
        robot_xy: tuple[float, float],
        xy: tuple[float, float],
        strategy: Strategy,
        extra: float = 0.0,
        others: Sequence[dict] = (),
        corridor: bool = True,
        object_yaw: float | None = None,
        plan: GraspPlan | None = None,
    ) -> list[tuple[float, float, float]]:
        """Standoff poses with room for the base around them and (with ``corridor``) a
        clear straight approach to the object, best first (``others``: perceived objects
        to keep clear of; ``object_yaw``: the measured yaw of a box or of a lying body's
        axis, for square approaches; ``plan``: the grasp, default the upright one)."""
        plan = plan or strategy.upright
        free = []
        for pose in strategy.standoff_poses(robot_xy, xy, extra, object_yaw, plan):
            if self.run_actor("clearance", pose[0], pose[1]) >= STANDOFF_CLEARANCE and (
                not corridor or self._corridor_clear(pose, xy, plan.reach, others)
            ):
                free.append(pose)
        if not free:
            raise ApproachError(
                f"no free standoff around ({xy[0]:.2f}, {xy[1]:.2f}): walls, "
                "furniture or other objects are in the way on every side"
            )
        return free

    def _corridor_clear(
        self, pose: tuple[float, float, float], xy: tuple[float, float], reach: float, others: Sequence[dict]
    ) -> bool:
        """Can the base drive straight in from ``pose`` until the hand, ``reach`` ahead of
        the base, is at the object?"""
        sx, sy, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        gx, gy = xy[0] - reach * c, xy[1] - reach * s  # base position when grasping
        for k in range(1, 5):  # the base's path: the map (obstacles marked) has room
            f = k / 4
            bx, by = sx + f * (gx - sx), sy + f * (gy - sy)
            if self.run_actor("clearance", bx, by) >= OUTLINE_REACH + BASE_MARGIN:
                continue  # nothing near the whole outline: no need to look closer
            centres, radius = outline_discs((bx, by, yaw))
            if any(self.run_actor("clearance", px, py) < radius + BASE_MARGIN for px, py in centres):
                return False
        for o in others:  # the open hand's path, from the base's front to the object
            r = float(o.get("radius", 0.05))
            if segment_distance((o["x"], o["y"]), (gx + 0.1 * c, gy + 0.1 * s), xy) < HAND_HALF_WIDTH + r:
                return False
        return True

    def _others(self, target: dict, strategy: Strategy) -> list[dict]:
        """Perceived objects other than the target in view now, as obstacles (x, y, radius).
        Around a lying target, anything within its length is taken for a part of it."""
        if not self.check_actor("object_glance"):
            return []
        xy = target_xy(target)
        own = strategy.length if target.get("pose") == "lying" else SAME_OBJECT
        return [
            {"x": d["x"], "y": d["y"], "radius": max(0.04, float(d.get("width", 0.08)) / 2) + 0.02}
            for d in self.run_actor("object_glance")
            if math.dist((d["x"], d["y"]), xy) > max(SAME_OBJECT, own)
        ]

    def _refine(self, target: dict, category: str, confirm: bool = False) -> dict:
        """Look again from close by, when a perception actor is available. With
        ``confirm``, a look that sees an object of no known category where the target
        should be, and the category nowhere near it, rejects the target."""
        if not self.check_actor("get_found"):
            return target
        seen = self.run_actor("get_found", category)
        if not seen or math.dist(target_xy(seen), target_xy(target)) > 0.3:
            if confirm:
                self._reject_if_something_else(target, category)
            # not seen, or a different object came into view: keep ours (from near, moved
            # to where an object of its size is seen)
            return self._unnamed_at_it(target)
        if ends_swapped(seen, target) and seen.get("confidence", 0.0) < target.get("confidence", 0.0):
            return target  # seen nearly end on, its base and top taken for each other
        return seen_again(target, seen)

    def _unnamed_at_it(self, target: dict) -> dict:
        """``target`` moved to an object of no known category seen at its place, from
        nearer than CONFIRM_RANGE, when that object has its size: from there perception
        misreads a lying box's faces, yet measures where it is. The localisation moves by
        a centimetre or two between two looks; the last one from the look pose would put
        the hand that far off, enough for the open fingers to close beside a 70 mm carton."""
        xy = target_xy(target)
        rx, ry, _ = self.run_actor("get_pose")
        if math.dist((rx, ry), xy) >= CONFIRM_RANGE[0]:
            return target
        other = self.run_actor("get_found", "unknown", near=list(xy), within=SAME_OBJECT)
        if not other or math.dist(target_xy(other), xy) > UNNAMED_GATE:
            return target
        for size in ("width", "height"):
            if (
                isinstance(target.get(size), (int, float))
                and abs(float(other.get(size) or 0.0) - float(target[size])) > UNNAMED_SIZE
            ):
                return target
        return {**target, "x": float(other["x"]), "y": float(other["y"])}

    def _reject_if_something_else(self, target: dict, category: str) -> None:
        """Raise ApproachError when, from close by, the object at the target's place is
        one of no known category: a distractor taken for the category from afar (a yellow
        mug for a lying carton at 2.7 m). The search is told, so that it does not send the
        robot back to it."""
        xy = target_xy(target)
        rx, ry, _ = self.run_actor("get_pose")
        near, far = CONFIRM_RANGE
        if not near <= math.dist((rx, ry), xy) <= far:
            return  # too far to tell shapes apart, or too near
        # what is at its place: the object seen most, or nearest, may be another one (a
        # piece of furniture near it), and then the thing taken for the target is never
        # asked about
        other = self.run_actor("get_found", "unknown", near=list(xy), within=SAME_OBJECT)
        if not other:
            return  # nothing else there: a missed look
        self.set_value("rejected", self.get_value("rejected")[-19:] + [(xy[0], xy[1], category)])
        self._pass_over(xy, category)
        raise ApproachError(
            f"no {category} at ({xy[0]:.2f}, {xy[1]:.2f}): seen from "
            f"{math.dist((rx, ry), xy):.2f} m, the object there is of no known category"
        )

    @actor(moves=True)
    def approach_object(self, target: dict, category: str | None = None) -> dict:
        """Drive to the category's standoff in front of ``target`` and face it.

        From a look distance the robot first faces the object and looks again (when
        perception is available): the target is re-measured, and other objects near it are
        marked on the planner's map and kept out of the approach. An object on a raised
        surface is looked at from farther (where the camera sees it) and the robot stays
        there, facing it: the pick drives straight in from there. Returns the target.

        Args:
            target: the object, as perception reports it: a dict with its axis x, y in
                the map frame [m] and usually its category
            category: whose strategy to use (can, bottle, carton, ...); None: the
                target's category

        Returns:
            the target as re-measured from close by, with its category
        """
        strategy = self._strategy(target, category)
        cat = strategy.category
        self.set_value("sighted_at", target_xy(target))
        target = self._where_now(target)
        xy = target_xy(target)
        for x, y, c in self.get_value("rejected"):
            # the retry of a target the close look rejected: the next look might call the
            # distractor by the category again, and the grasp would close on it
            if c == cat and math.dist((x, y), xy) < SAME_OBJECT:
                raise ApproachError(
                    f"no {cat} at ({xy[0]:.2f}, {xy[1]:.2f}): a close look saw an "
                    f"object of no known category there before"
                )
        plan = self._plan(strategy, target)
        look = self._look_distance(target, strategy)
        # a raised object (on a table): from nearer than its look distance the camera sees
        # nothing of it, and the look's estimate is only as good as the localisation's
        # heading (1 degree is 3 cm at 1.8 m). So the pick drives straight in from the
        # look pose, where the estimate and the heading to it are the same belief.
        raised = float(target.get("z") or 0.0) > RAISED
        direct = False
        for step in ("look", "standoff"):
            # face it, look (again), and keep what else is around it out of the way
            self._face(xy, strategy)
            if step == "standoff":
                target = self._refine(target, cat, confirm=True)
                xy = target_xy(target)
                if direct:
                    break
            others = self._others(target, strategy)
            self.run_actor("mark_obstacles", others)
            rx, ry, _ = self.run_actor("get_pose")
            if step == "look":
                here = math.dist((rx, ry), xy)
                if not look or (CONFIRM_RANGE[0] <= here <= look + 0.3 and not raised):
                    continue  # close enough already
                # (nearer than the confirming look's range, it backs off to the look pose:
                # from too near no look can reject a distractor the search took for the
                # category, and it would be grasped and carried off)
                # (a box only if square to a side: its grasp comes straight in from here)
                square_enough = not _upright_box(target, plan) or self._off_sides(target, plan) <= RAISED_SQUARE
                if (
                    raised
                    and abs(here - look) <= 0.3
                    and square_enough
                    and self._corridor_clear((rx, ry, math.atan2(xy[1] - ry, xy[0] - rx)), xy, plan.reach, others)
                ):
                    direct = True
                    continue  # a look pose already, the way in clear
                looks = _look_plans(target, plan, raised)
                poses = []
                # a raised object is seen from a band of distances only, and its grasp
                # comes straight in from the look: where the look distance has no room (a
                # wall behind the robot), a little nearer or farther
                steps = RAISED_LOOK_STEPS if raised else (0.0,)
                for look_plan, distance in ((p, look + k) for p in looks for k in steps if look + k <= MAX_LOOK):
                    try:
                        poses = self._free_standoff(
                            (rx, ry),
                            xy,
                            strategy,
                            distance - plan.reach - strategy.approach.standoff,
                            others,
                            object_yaw=target.get("yaw"),
                            plan=look_plan,
                        )
                        break
                    except ApproachError:
                        continue
                if not poses:
                    continue  # no room to look from there (a cramped corner): go closer
                direct = raised  # the look poses have a clear way in (the corridor)
            else:
                plan = self._plan(strategy, target)  # the close look may see it otherwise
                try:
                    poses = self._grasp_standoffs((rx, ry), target, strategy, plan, others)
                except ApproachError:
                    # no side to take it from: later searches pass it over, else each one
                    # comes back to it and the mission spends every fetch there
                    self._pass_over(xy, cat)
                    raise
                poses = self._finger_room_first(poses, xy, plan, target)
            self._goto_first(self._fresh_views_first(poses, xy), xy, target, strategy.length, others)
        self._face(xy, strategy)
        # a last look from the standoff, the nearest and most precise one: the way here
        # may have moved the localisation's estimate by a few centimetres
        target = self._refine(target, cat)
        xy = target_xy(target)
        plan = self._plan(strategy, target)
        square = RAISED_SQUARE if direct and _upright_box(target, plan) else plan.tolerance
        if self._off_sides(target, plan) > square:
            # seen from here, facing it would bring the hand too far off the side it must
            # come from (a lying body: across it): it is not where the standoff was
            # chosen for (nudged, or seen better now). Line up with it again; from a
            # raised object's look pose, at the same distance: the camera sees it there.
            rx, ry, _ = self.run_actor("get_pose")
            extra = math.dist((rx, ry), xy) - plan.reach - strategy.approach.standoff if direct else 0.0
            try:
                poses = self._free_standoff(
                    (rx, ry), xy, strategy, extra, others=others, object_yaw=object_yaw(target, plan), plan=plan
                )
            except ApproachError:
                poses = []
            if poses:
                self._goto_first(poses, xy, target, strategy.length, others)
                self._face(xy, strategy)
                target = self._refine(target, cat)
                xy = target_xy(target)
        self._face(xy, strategy)
        return {**target, "category": cat}

    def _grasp_standoffs(
        self, robot_xy: tuple[float, float], target: dict, strategy: Strategy, plan: GraspPlan, others: list[dict]
    ) -> list[tuple[float, float, float]]:
        """The free standoffs for ``plan``. A leaning or lying target is taken from some
        sides only; where none has room, it is approached as an upright one would be: a
        pose measured from afar is a guess, and the look from the standoff measures it
        again (from afar an upright bottle can be called leaning, its lean side towards a
        wall, or an upright carton lying)."""
        xy = target_xy(target)
        try:
            return self._free_standoff(
                robot_xy, xy, strategy, others=others, object_yaw=object_yaw(target, plan), plan=plan
            )
        except ApproachError:
            if target.get("pose") in (None, "upright"):
                raise
        return self._free_standoff(robot_xy, xy, strategy, others=others, plan=strategy.upright)

    def _finger_room_first(
        self, poses: list[tuple[float, float, float]], xy: tuple[float, float], plan: GraspPlan, target: dict
    ) -> list[tuple[float, float, float]]:
        """Standoff ``poses`` from which the open fingers, coming in beside an object on
        the floor, stay off the map's obstacles first (else in their order). A finger that
        runs into furniture the object stands against stops the base short, its wheels
        slipping, and the fingertips pinch the object (a bottle against a bench's side,
        the hand coming along the bench, held at 60 of its 70 mm)."""
        if float(target.get("z") or 0.0) > RAISED or plan.pitch > math.radians(45):
            return poses  # above a table, or from above: the fingers are clear of the map
        side = 0.5 * plan.open_width + FINGER_THICKNESS

        def blocked(pose: tuple[float, float, float]) -> bool:
            c, s = math.cos(pose[2]), math.sin(pose[2])
            return any(
                self.run_actor("clearance", xy[0] + a * c - k * side * s, xy[1] + a * s + k * side * c) <= 0.0
                for a in FINGER_SPAN
                for k in (1, -1)
            )

        flags = [blocked(pose) for pose in poses]
        return [p for p, b in zip(poses, flags) if not b] + [p for p, b in zip(poses, flags) if b]

    def _look_distance(self, target: dict, strategy: Strategy) -> float:
        """How far from the target [m] the base stops for the closer look: the strategy's
        look distance; for an object on a raised surface, far enough that the camera sees
        LOOK_SEEN of its height (up to MAX_LOOK): nearer, the camera looks under it (and
        the pick keeps the far, less precise estimate)."""
        look = strategy.approach.look_distance
        z = float(target.get("z") or 0.0)
        if not look or z <= RAISED:
            return look
        tall = strategy.length if target.get("pose") != "lying" else float(target.get("width") or 0.07)
        view = self._camera_view()
        if view is None:
            return look
        cam_x, cam_z, slope = view
        if slope <= 0.0:
            return look
        need = cam_x + (z + LOOK_SEEN * tall - cam_z) / slope
        return min(max(look, need), MAX_LOOK)

    def _camera_view(self) -> tuple[float, float, float] | None:
        """The camera's mount and the upper edge of its view, in the base frame: (x, z)
        of the camera [m] and the slope (rise per metre) of its highest ray straight ahead;
        None without a posed RGB-D camera. The mount is fixed: measured once."""
        view = self.get_value("camera_view")
        if view is not None:
            return view
        if not self.check_actor("rgbd"):
            return None
        try:
            frame = self.run_actor_mode("rgbd", "timed", 2.0)
        except ActorbtError:
            return None
        T = np.linalg.inv(frame.T_map_base) @ frame.T_map_cam
        k = frame.intrinsics
        ray = T[:3, :3] @ np.array([0.0, -k.cy / k.fy, 1.0])  # image row 0, centre column
        view = (float(T[0, 3]), float(T[2, 3]), float(ray[2] / math.hypot(ray[0], ray[1])))
        self.set_value("camera_view", view)
        return view

    def _off_sides(self, target: dict, plan: GraspPlan) -> float:
        """How far [rad] the hand, the base facing the target from where it is, would
        come off the nearest side the plan may grasp it from (0: any side will do)."""
        x, y, _ = self.run_actor("get_pose")
        gx, gy = grasp_xy(target, plan)
        return plan.off_sides(math.atan2(gy - y, gx - x), object_yaw(target, plan))

    def _goto_first(
        self,
        poses: list[tuple[float, float, float]],
        xy: tuple[float, float],
        target: dict | None = None,
        length: float = 0.0,
        others: Sequence[dict] = (),
    ) -> None:
        """Go to the first of ``poses`` that the base can reach (up to three tries). With
        ``target``, the way there keeps off it (``target_marks``; ``others`` are the
        marks already made, kept); if no way does, the base goes there as before."""
        errors = []
        for pose in poses[:3]:
            marks = target_marks(target, length, pose[:2]) if target is not None else []
            try:
                for keep_off in [True, False] if marks else [False]:
                    self.run_actor("mark_obstacles", list(others) + (marks if keep_off else []))
                    try:
                        self.run_actor("goto", *pose)
                        return
                    except ActorbtError as e:
                        errors.append(str(e))
            finally:
                if marks:
                    self.run_actor("mark_obstacles", list(others))
        raise ApproachError(f"could not reach a standoff near ({xy[0]:.2f}, {xy[1]:.2f}): " + "; ".join(errors))


def _look_plans(target: dict, plan: GraspPlan, raised: bool) -> list[GraspPlan]:
    """``plan`` with the sides the closer look may come from, best first (its standoffs
    at the look distance are the look poses). A look needs no particular side (a box's
    grasp does), but:
    - a lying body is looked at from aside: seen end on it is often missed, or its ends
      mistaken (where no aside view has room, from any side: from end on, a look still
      tells a distractor from the category, which a grasp without a look cannot);
    - a box on a table from the sides it is grasped from, where one has room: its grasp
      comes straight in from the look pose (RAISED_SQUARE)."""
    if target.get("pose") == "lying":
        return [replace(plan, sides=sides, one_way=False) for sides in (ASIDE, ())]
    if raised and _upright_box(target, plan):
        return [plan, replace(plan, sides=())]
    return [replace(plan, sides=(), one_way=False)]


def _upright_box(target: dict, plan: GraspPlan) -> bool:
    """Whether ``plan`` holds an upright object from some of its sides only (a box)."""
    return bool(plan.sides) and target.get("pose") in (None, "upright")
