"""Approach, pick and place with the category's strategy, as actors.

A target is a dict with at least ``x``, ``y`` (the object's axis in the map frame [m])
and ``category``, as perception reports it. These actors call the robot's actors by name
(``goto``, ``mini_turn``, ``move_to_pose``, ...), so they run unchanged on any robot that
provides them.

The actors and their helpers live in modules by concept, and every name those define is
importable from here: ``catch_geometry`` (the pure geometry: outline, target marks,
views, put-down spots), ``catch_approach`` (``approach_object``), ``catch_place``
(``carry_pose``, ``place``, ``place_on``) and ``catch_errors``; this module keeps
``Catcher`` with its shared helpers, ``pick`` and the grip checks.
"""

from __future__ import annotations

import math
from typing import Any

from bt_engine import ActorbtError, SubSystem, actor
from categories.check import TEST_LIFT  # the first, short lift that checks the grip [m]

# Everything the modules define, importable from actors.catch as before the split
from .catch_approach import (
    ASIDE,
    CONFIRM_RANGE,
    FINGER_SPAN,
    FINGER_THICKNESS,
    HAND_HALF_WIDTH,
    LOOK_SEEN,
    MAX_LOOK,
    RAISED,
    RAISED_LOOK_STEPS,
    UNNAMED_GATE,
    UNNAMED_SIZE,
    Approaching,
)
from .catch_errors import ApproachError, GraspError
from .catch_geometry import (
    BASE_MARGIN,
    BASE_OUTLINE,
    FINGERTIPS,
    MARK_MARGIN,
    MARK_SPACING,
    NEW_VIEW,
    OUTLINE_REACH,
    PLACE_EDGE_MARGIN,
    PLACE_SPACING,
    SAME_OBJECT,
    STANDOFF_CLEARANCE,
    ends_swapped,
    fresh_views_first,
    grasp_xy,
    object_yaw,
    outline_discs,
    seen_again,
    segment_distance,
    surface_spots,
    target_marks,
    target_xy,
)
from .catch_place import (
    GENTLE_RELEASE,
    MIN_PLACE_REACH,
    PLACE_ABOVE,
    PLACE_INSET,
    PLACE_SHORT,
    PLACE_STANDOFF,
    RELEASE_CLEARANCE,
    Placing,
)
from .category_check import check_registered
from .ros_conv import wrap
from .strategies import GraspPlan, Strategy, strategy_for

GIVE_UP = 3  # failed grasps of one object after which the search passes it over
DRIVE_IN_TOLERANCE = 0.015  # how close the drive around an object must end [m]: the
#                             fingers are 70 mm long
PUSHED = 0.45  # a failed grasp may push the object this far [m]
LOOK_AROUND = math.radians(35)  # after a failed grasp, also look this far to either side
MIN_LOOK = 0.3  # [m] nearer than this, the camera sees too little of an object
CHORD_MARGIN = 0.004  # [m] fingers that stall this much narrower than a round body is
#                             wide closed on a chord of it, at their tips
PINCH_MIN_CHORD = 0.8  # of a round body's width: on a narrower chord the tips meet its
#                             side more than 37 degrees off square and squeeze it out
LONG_DRIVE = 0.25  # [m] a longer drive in faces the object again on the way
LONG_DRIVE_SPEED = 0.22  # [m/s] the first part of it (the Waffle's top speed is 0.26)
REGRASP_BACK = 0.05  # [m] the base backs off this far before it grasps again
SLIP = 0.004  # [m] a held object slipped when the fingers close this much
#                             narrower than they held it after the pick (and narrower than
#                             the grasp's range)


def _holds(plan: GraspPlan, grip: dict) -> bool:
    """Does a gripper result (Manipulator.close) mean the object is held? The fingers
    stalled on something, at a width that fits the grasp."""
    return bool(grip["stalled"]) and plan.holding(grip["width"])


def _held_side(plan: GraspPlan, grip: dict) -> GraspPlan | None:
    """The plan of the side the fingers hold the object across (``GraspPlan.side_plans``),
    None when they hold it across none."""
    return next((p for p in plan.side_plans() if _holds(p, grip)), None)


def _ranges_text(plan: GraspPlan) -> str:
    return " or ".join(f"{p.closed_min * 1000:.0f}..{p.closed_max * 1000:.0f}" for p in plan.side_plans())


def _beyond_tips(plan: GraspPlan, grip: dict) -> float:
    """How far [m] the axis of a round body is beyond the line the fingers closed on it
    along, 0 when they closed across its axis (or it is no round body held from the side).
    The fingers stalled narrower than the body (``plan.across``) but within the range the
    pick takes for holding it: they cannot close on a chord of it between their roots and
    their tips, so they pinched it with their tips, the hand short of it (the base stopped
    short, or pushed it ahead): a grip that may not last the carry. Also a little narrower
    than that range, down to PINCH_MIN_CHORD of the body."""
    if plan.sides or plan.pitch > math.radians(45) or not grip["stalled"]:
        return 0.0
    body, w = plan.across, grip["width"]
    if not min(plan.closed_min, PINCH_MIN_CHORD * body) <= w <= body - CHORD_MARGIN:
        return 0.0  # narrower still: a miss (squeezed out, tipped), which the tree retries
    return math.sqrt((body / 2) ** 2 - (w / 2) ** 2)


def _still_holds(plan: GraspPlan, held_width: float, grip: dict) -> bool:
    """Does a grip check (``close`` again) mean the object picked at ``held_width`` [m] is
    still held? The fingers stall on it, no more than SLIP narrower than they held it
    (or within the grasp's range): squeezing, they creep in a little over a carry, and
    one that slips out closes them fully."""
    return (
        bool(grip["stalled"])
        and grip["width"] <= plan.closed_max
        and grip["width"] >= min(plan.closed_min, held_width - SLIP)
    )


def _grip_text(grip: dict) -> str:
    how = "stalled" if grip["stalled"] else "closed" if grip["reached_goal"] else "stopped"
    return f"fingers {how} at {grip['width'] * 1000:.0f} mm"


class Catcher(Approaching, Placing, SubSystem):
    """Per-category approach, pick and place."""

    def __init__(self) -> None:
        super().__init__()
        check_registered()  # a category that cannot work fails now, not at the object
        self.set_value("holding", None)
        self.set_value("held_plan", None)  # the GraspPlan the held object was picked with
        self.set_value("failed_views", [])  # (x, y, heading) of grasps that failed
        self.set_value("moved_to", None)  # (was x, y; the detection seen after): where
        #                                      a failed grasp left the object
        self.set_value("lost_at", None)  # (x, y): the sighting whose failed grasp left
        #                                      the object nowhere the look round saw
        self.set_value("rejected", [])  # (x, y, category): a close look saw something else there
        self.set_value("put_down", [])  # (x, y): where place_on put objects down
        self.set_value("camera_view", None)  # see _camera_view
        self.set_value("sighted_at", None)  # (x, y): the target approach_object was last given

    def _fresh_views_first(
        self, poses: list[tuple[float, float, float]], xy: tuple[float, float]
    ) -> list[tuple[float, float, float]]:
        return fresh_views_first(poses, xy, self.get_value("failed_views"))

    def _remember_failed_view(self, xy: tuple[float, float], category: str) -> None:
        """Note a failed grasp of the object at ``xy``; after GIVE_UP of them (bt_catch's
        attempts) the search is told to pass it over, as after a close look that rejects
        it: a distractor the looks take for the category (a lego brick for a lying carton)
        would otherwise draw every later search back to it, while the object sought waits
        elsewhere."""
        _, _, yaw = self.run_actor("get_pose")
        views = self.get_value("failed_views")[-9:] + [(xy[0], xy[1], yaw)]
        self.set_value("failed_views", views)
        if sum(math.dist((x, y), xy) <= SAME_OBJECT for x, y, _ in views) >= GIVE_UP:
            self._pass_over(xy, category)

    def _pass_over(self, xy: tuple[float, float], category: str) -> None:
        """Tell the search to pass over the ``category`` seen at ``xy`` from now on, and
        the sighting that sent the approach here when the look moved the target: else the
        search sends the robot back to it, and on to the same object, fetch after fetch."""
        if not self.check_actor("reject_sighting"):
            return
        self.run_actor("reject_sighting", xy[0], xy[1], category)
        sighted = self.get_value("sighted_at")
        if sighted is not None and math.dist(sighted, xy) > SAME_OBJECT:
            self.run_actor("reject_sighting", sighted[0], sighted[1], category)

    def _look_for_it(self, xy: tuple[float, float], category: str) -> None:
        """After a failed grasp of the object at ``xy`` (the base backed off, facing it):
        find where the grasp left it, looking ahead and to either side, and remember it
        for the next approach, which then starts from there (``moved_to``)."""
        if not self.check_actor("object_glance"):
            return
        turned = 0.0
        for turn in (0.0, LOOK_AROUND, -2 * LOOK_AROUND):
            if turn:
                self.run_actor("mini_turn", turn)
                turned += turn
            near = [
                d
                for d in self.run_actor("object_glance")
                if d["category"] == category and math.dist((d["x"], d["y"]), xy) <= PUSHED and d["distance"] >= MIN_LOOK
            ]
            if near:
                seen = min(near, key=lambda d: math.dist((d["x"], d["y"]), xy))
                self.set_value("moved_to", (xy, seen))
                break
        else:
            self.set_value("lost_at", self.get_value("sighted_at"))
        if turned:
            self.run_actor("mini_turn", -turned)

    def _where_now(self, target: dict) -> dict:
        """``target``, or where a failed grasp of it left it (see ``_look_for_it``). An
        object the failed grasp sent out of sight (a slipping can rolls off) is not
        where it was: going back there, every attempt would close on the empty floor."""
        lost = self.get_value("lost_at")
        if lost is not None and tuple(lost) == target_xy(target):
            # the same sighting retried; a new search's sighting there is looked at afresh
            raise ApproachError(
                f"no {target.get('category') or 'object'} at ({lost[0]:.2f}, {lost[1]:.2f}) "
                f"any more: the failed grasp there left it where the look round did not see it"
            )
        moved = self.get_value("moved_to")
        if moved is None:
            return target
        was, seen = moved
        if math.dist(was, target_xy(target)) > PUSHED:  # another object
            return target
        return seen_again(target, seen)

    def _strategy(self, target: Any, category: str | None) -> Strategy:
        cat = category or (target.get("category") if isinstance(target, dict) else None)
        if not cat:
            raise ActorbtError("no category given and the target names none")
        return strategy_for(cat)

    def _face(self, xy: tuple[float, float], strategy: Strategy) -> float:
        """Turn until the object is straight ahead; returns its distance [m]."""
        for _ in range(3):
            x, y, yaw = self.run_actor("get_pose")
            bearing = wrap(math.atan2(xy[1] - y, xy[0] - x) - yaw)
            if abs(bearing) <= strategy.approach.max_bearing:
                return math.hypot(xy[0] - x, xy[1] - y)
            self.run_actor("mini_turn", bearing)
        raise ApproachError(f"could not face the object: {math.degrees(bearing):.1f} deg off")

    @staticmethod
    def _plan(strategy: Strategy, target: dict) -> GraspPlan:
        """The grasp for the target's pose (``pose`` as perception reports it: upright,
        lying or tilted); GraspError when the category has none for it."""
        pose = target.get("pose") or "upright"
        width = target.get("width")
        plan = strategy.plan_for(pose, float(width) if isinstance(width, (int, float)) else None)
        if plan is None:
            raise GraspError(f"the {strategy.category} strategy has no grasp for an object {pose}")
        return plan

    @actor(moves=True)
    def pick(self, target: dict, category: str | None = None) -> dict:
        """Grasp ``target`` with the category's strategy and lift it.

        Fails with GraspError when the fingers close on nothing (and backs off first),
        and before moving anything when the robot is delocalised (require_localised).

        Args:
            target: the object, as approach_object returns it: a dict with its axis x, y
                in the map frame and its base z [m], and usually its category
            category: whose strategy to use (can, bottle, carton, ...); None: the
                target's category

        Returns:
            what is held: category, and width (the finger opening) [m]
        """
        strategy = self._strategy(target, category)
        g = self._plan(strategy, target)
        xy = grasp_xy(target, g)
        self.run_actor("require_localised")  # never grasp where the map pose is a guess
        height = float(target.get("z", 0.0)) + g.height  # the object may stand on something
        self.run_actor("open", g.open_width)
        # over a lying object the hand comes in high and goes down once in place
        above = height + (g.lift if g.pitch > math.radians(45) else 0.0)
        self.run_actor("move_to_pose", g.reach, 0.0, above, g.pitch)
        distance = self._face(xy, strategy)
        driven = 0.0
        if distance - g.reach > LONG_DRIVE:
            # from a look pose (a raised object), not a standoff: most of the way, then
            # face it again from near (mini_turn leaves up to half a degree: 15 mm at
            # 1.8 m) and measure what is left on the map. Not on the odometry: a wheel's
            # scale error (2 % is common) leaves the hand 3-4 cm short after 1.5 m, enough
            # for the fingertips to close in front of a bottle, where the localisation is
            # within about a centimetre, and alike at the look.
            # Briskly: the gyro's drift, which bends the way, grows with the time it takes.
            driven += self.run_actor(
                "mini_walk",
                distance - g.reach - strategy.approach.standoff,
                speed=LONG_DRIVE_SPEED,
                tolerance=DRIVE_IN_TOLERANCE,
            )
            distance = self._face(xy, strategy)
        driven += self._drive_in(distance - g.reach)
        if above != height:
            self.run_actor("move_to_pose", g.reach, 0.0, height, g.pitch)
        grip = self.run_actor("close")
        deeper = _beyond_tips(g, grip)
        if deeper > 0:
            # the fingertips pinched it, its axis ahead of them: a grip that slips or
            # twists out. Where they felt it is known better than any look: back off a
            # little, line up with that and grasp again (driving in with the fingers
            # around it, the fingertips would push it ahead: they grip).
            xy = self._felt_xy(g, grip, deeper)
            self.run_actor("open", g.open_width)
            driven += self.run_actor("mini_walk", -REGRASP_BACK)
            distance = self._face(xy, strategy)
            driven += self._drive_in(distance - g.reach)
            grip = self.run_actor("close")
        held_side = _held_side(g, grip)
        if held_side is None:
            self._remember_failed_view(xy, strategy.category)
            self._back_off(driven, g)
            self._look_for_it(xy, strategy.category)
            raise GraspError(
                f"{strategy.category} grasp missed: {_grip_text(grip)}, expected "
                f"them to stall on it at {_ranges_text(g)} mm"
            )
        g = held_side  # the slip checks expect the width across the side held
        # Test lift: a slip shows when the fingers close again, and the object drops only
        # a little (a can dropped from the full lift height may fall over).
        for x, z in ((g.reach, height + TEST_LIFT), self._lift_pose(g, height)):
            try:
                self.run_actor("move_to_pose", x, 0.0, z, g.pitch)
            except ActorbtError as e:
                # put it back down and let go: held on, it would be carried to the next
                # try and dropped there, perhaps off a table's edge
                self._put_back(g, height)
                self._back_off(driven, g)
                raise GraspError(f"{strategy.category} could not be lifted: {e}") from e
            grip = self.run_actor("grip_check")
            if not _holds(g, grip):
                self._remember_failed_view(xy, strategy.category)
                self._back_off(driven, g)
                self._look_for_it(xy, strategy.category)
                raise GraspError(f"{strategy.category} slipped out while lifting ({_grip_text(grip)})")
        held = {"category": strategy.category, "width": grip["width"], "pose": target.get("pose") or "upright"}
        self.set_value("holding", held)
        self.set_value("held_plan", g)
        self.set_value("moved_to", None)
        self.set_value("lost_at", None)
        return held

    def _put_back(self, g: GraspPlan, height: float) -> None:
        """Lower the held object to where it was grasped (as near as the arm gets)."""
        try:
            self.run_actor("move_to_pose", g.reach, 0.0, height + 0.003, g.pitch)
        except ActorbtError:
            pass  # the arm stays where it stopped: let go there

    def _felt_xy(self, g: GraspPlan, grip: dict, beyond: float) -> tuple[float, float]:
        """The map x, y of a round body's axis the fingertips closed on (``beyond`` [m]
        ahead of them, ``grip["centre"]`` to the left of the hand's axis)."""
        x, y, yaw = self.run_actor("get_pose")
        ahead, left = g.reach + FINGERTIPS + beyond, float(grip.get("centre") or 0.0)
        c, s = math.cos(yaw), math.sin(yaw)
        return x + c * ahead - s * left, y + s * ahead + c * left

    def _lift_pose(self, g: GraspPlan, height: float) -> tuple[float, float]:
        """(x, z) of the full lift: the plan's lift, a little drawn in. From a table the
        arm may not reach that high (its wrist is 0.25 m from the shoulder at most), so it
        lifts as high as it reaches there, drawing the hand in further first."""
        top, bottom = height + g.lift, height + TEST_LIFT + 0.01
        for x in (g.reach - 0.02, g.reach - 0.05, g.reach - 0.08):
            z = top
            while z >= bottom:
                if self.run_actor("reachable", x, 0.0, z, g.pitch):
                    return x, z
                z -= 0.01
        return g.reach, height + TEST_LIFT  # stay where the test lift held it

    @actor(moves=True)
    def grip_check(self) -> dict:
        """Close the gripper again and return the controller's result (see ``close``):
        it stalls on what the fingers hold, and reaches the closed end when they are empty."""
        return self.run_actor("close")

    @actor(moves=True)
    def verify_grasp(self) -> bool:
        """True while the gripper holds what the last pick took: closing the gripper
        again, the fingers stall at a width that fits the object, and no narrower than
        they held it after the pick (see ``_still_holds``)."""
        held = self.get_value("holding")
        if not held:
            return False
        return _still_holds(self.get_value("held_plan"), float(held.get("width") or 0.0), self.run_actor("grip_check"))

    def _drive_in(self, distance: float) -> float:
        """Drive straight in by ``distance`` [m]; returns how far it drove. The walk stops
        as soon as it is within DRIVE_IN_TOLERANCE, that is short of the goal: it aims
        half the tolerance beyond, so that it stops within half of it either side (the
        pads then cover the middle of a box, not just its near edge)."""
        return self.run_actor("mini_walk", distance + 0.5 * DRIVE_IN_TOLERANCE, tolerance=DRIVE_IN_TOLERANCE)

    def _back_off(self, distance: float, plan: GraspPlan) -> None:
        self.run_actor("open", plan.open_width)
        if plan.pitch > math.radians(45):  # from above: lift the open hand out first
            self.run_actor("move_to_pose", plan.reach, 0.0, plan.height + plan.lift, plan.pitch)
        self.run_actor("mini_walk", -max(0.05, distance))
        self.run_actor("home")
