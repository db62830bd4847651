"""How a category's object is approached and grasped: the numbers a strategy supplies.

The arm of the reference robot reaches the floor only in a narrow band in front of the
base, so every strategy grasps the same way: the base stops at a standoff facing the
object, the arm extends the open gripper to the grasp pose, and the base drives the
fingers around the object before they close. What differs per category is the numbers:
the standoff, which part is held (height, tool pitch), the opening, the lift, what a
successful grasp looks like, and (for a box) from which sides the hand may come.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Approach:
    """How the base approaches an object.

    Attributes:
        reach: distance from base_footprint to the object's axis when grasping [m].
        standoff: extra distance kept before the final straight approach [m]; the arm
            unfolds there, clear of the object.
        max_bearing: largest bearing error accepted before the final approach [rad]; the
            base turns until the object is this close to straight ahead.
        look_distance: where the base stops to take a closer look first [m], or 0.
    """

    reach: float = 0.27
    standoff: float = 0.12
    max_bearing: float = math.radians(0.6)
    look_distance: float = 0.75


@dataclass(frozen=True)
class Grasp:
    """How the gripper holds an object.

    Attributes:
        height: height of the held part above the object's base [m] ("which part to hold").
        pitch: tool angle below the horizontal [rad] while grasping.
        open_width: finger opening before closing [m].
        closed_min, closed_max: finger opening that means "holding it" [m]; less is a
            miss (the fingers closed on nothing), more is a jam. None (the default): derived
            from the width the fingers close on at ``height`` (:func:`derived_window`).
        lift: how far to lift after closing [m].
    """

    height: float
    pitch: float = 0.0
    open_width: float = 0.085
    closed_min: float | None = None
    closed_max: float | None = None
    lift: float = 0.12


@dataclass(frozen=True)
class TopGrasp:
    """How an object lying on its side is held: from above, the hand pointing down, the
    fingers closing across the body while the base faces along the object's axis (a
    box's long side; the arm has no wrist roll, so the fingers always close across the
    base's heading).

    Attributes:
        reach: tool position ahead of base_footprint while grasping [m]; pointing down,
            the arm reaches 0.10..0.22 m.
        above_axis: tool height above the lying body's axis (a box: the middle of its
            height) [m]: the finger pads span it and the fingertips stay clear of the floor.
        lift: how far to lift after closing [m].
        slack: the fingers stalled between the body's width minus the first and plus
            the second [m] mean it is held.
    """

    reach: float = 0.19
    above_axis: float = 0.015
    lift: float = 0.12
    slack: tuple[float, float] = (0.012, 0.008)


@dataclass(frozen=True)
class GraspPlan:
    """One way of holding an object, in the base's frame while grasping: the tool at
    (``reach``, 0, object base z + ``height``) with ``pitch``; the base faces the object
    along one of ``sides`` (headings relative to the object's yaw; empty: any)."""

    reach: float
    height: float
    pitch: float
    open_width: float
    closed_min: float
    closed_max: float
    lift: float
    sides: tuple[float, ...] = ()
    one_way: bool = False  # only along sides, never from the opposite face
    offsets: tuple[float, ...] = (0.0,)  # one way: headings off each side [rad] the hand
    #                                       may also come from (a wall may be close)
    widths: tuple[float, ...] = ()  # the width across the object from each of
    #                                       ``sides`` [m] (a box's); the closed range fits the first

    def side_plans(self) -> tuple[GraspPlan, ...]:
        """This plan for each of its ``sides``, the first as declared: the closed range
        moved by the width across that side (a box's wider side fits the open hand too,
        where the narrow one has no room for the base: a carton at a table's edge, held
        across its 70 mm side at 71..77 mm). Which side the hand came to is told by where
        the fingers stall: a box's yaw from afar may swap its sides (from 2 m a 45 mm side
        can be taken for the 70 mm one)."""
        if not self.widths or len(self.widths) != len(self.sides):
            return (self,)
        return (self,) + tuple(self.shifted(w - self.widths[0]) for w in self.widths[1:])

    def shifted(self, by: float) -> GraspPlan:
        """This plan holding a body ``by`` [m] wider: its closed range moved by that,
        kept short of the opening."""
        return replace(
            self,
            closed_min=self.closed_min + by,
            closed_max=min(self.closed_max + by, self.open_width - CLOSED_BELOW_OPEN),
        )

    def holding(self, closed_width: float) -> bool:
        return self.closed_min <= closed_width <= self.closed_max

    @property
    def tolerance(self) -> float:
        """How far off its ``sides`` [rad] the hand may come and still close around the
        object: any heading for a round one (no sides); from above, across a lying body,
        as far as its offsets go (LYING_OFFSETS); otherwise its offsets and
        SIDE_TOLERANCE beyond them (a box's narrow side, a leaning body)."""
        if not self.sides:
            return math.pi
        reach = max(abs(o) for o in self.offsets)
        if self.pitch > math.radians(45):
            return max(reach, max(LYING_OFFSETS)) + math.radians(1)
        return reach + SIDE_TOLERANCE

    def off_sides(self, heading: float, object_yaw: float | None) -> float:
        """How far [rad] a hand coming along ``heading`` is off the nearest of the plan's
        sides of an object whose yaw is ``object_yaw`` (0 without sides or yaw)."""
        if not self.sides or object_yaw is None:
            return 0.0
        flips = (0.0,) if self.one_way else (0.0, math.pi)
        return min(abs(_wrap(heading - object_yaw - s - f)) for s in self.sides for f in flips)

    @property
    def across(self) -> float:
        """The width the fingers close on [m], from the range that means holding it."""
        return 0.5 * (self.closed_min + self.closed_max)


#: an object's sides the hand may come from: any (round objects)
ANY_SIDE: tuple[float, ...] = ()
#: a leaning object is held as if upright, the hand coming along its lean or up to 30
#: degrees off it: the fingers close around its body all the same
TILTED_OFFSETS = tuple(math.radians(a) for a in (0, 15, -15, 30, -30))
#: from above, the pads (30 mm wide) close across a lying body only when the hand is
#: nearly square to it: 8 degrees off, a 70 mm body spans 75 mm of an 85 mm opening
LYING_OFFSETS = tuple(math.radians(a) for a in (0, 8, -8))
#: the fingers stalled this much short of the opening still mean holding (no jam) [m]
CLOSED_BELOW_OPEN = 0.002


def derived_window(width: float, open_width: float) -> tuple[float, float]:
    """(closed_min, closed_max) [m] for a body ``width`` [m] across: the fingers stall up
    to 10 mm narrower (the pads press in, or close on a chord near the fingertips) and up
    to 8 mm wider (a body met a little off square), short of the opening."""
    return round(width - 0.010, 4), round(min(width + 0.008, open_width - CLOSED_BELOW_OPEN), 4)


#: a box upright (held across its narrow side) or a leaning body: the hand may come this
#: far beyond its offsets (a 45 x 70 mm carton 15 degrees off spans 62 mm)
SIDE_TOLERANCE = math.radians(15)


@dataclass(frozen=True)
class Strategy:
    """A category's approach and grasp.

    ``sides`` are the headings [rad], relative to the object's yaw, from which the hand may
    come, best first (a box is held across its narrow side); empty: any heading.
    """

    category: str
    approach: Approach
    grasp: Grasp
    description: str = ""
    sides: tuple[float, ...] = ANY_SIDE
    lying: tuple[GraspPlan, ...] = ()  # how it is held lying on its side: one per face
    #                                     it may lie on (a box's differ in width), or none
    length: float = 0.0  # the object's largest extent [m]
    side_widths: tuple[float, ...] = ()  # the width across the object from each of ``sides``

    @property
    def upright(self) -> GraspPlan:
        g = self.grasp
        # the window is filled in by Category.__post_init__, which every Strategy comes from
        assert g.closed_min is not None and g.closed_max is not None
        return GraspPlan(
            self.approach.reach,
            g.height,
            g.pitch,
            g.open_width,
            g.closed_min,
            g.closed_max,
            g.lift,
            self.sides,
            widths=self.side_widths,
        )

    def plan_for(self, pose: str | None, width: float | None = None) -> GraspPlan | None:
        """The grasp for an object standing ``upright`` (or of unknown pose), ``lying`` on
        its side, or ``tilted`` (leaning on something): held as if upright, the hand coming
        from the side its base is on (heading = the direction it leans to, its ``yaw``), so
        that the top leans away from the hand and the fingers close across the body (a
        box: across the side ``width`` perception measured across the lean);
        None when the category has none for that pose. Lying, the face whose width across
        fits ``width`` (as perception measured it) is held, None if none does; without a
        width, the first."""
        if pose == "lying":
            if not self.lying:
                return None
            if width is None:
                return self.lying[0]
            fits = [p for p in self.lying if p.holding(width)]
            return min(fits, key=lambda p: abs(p.across - width)) if fits else None
        if pose == "tilted":
            plan = replace(self.upright, sides=(0.0,), one_way=True, offsets=TILTED_OFFSETS, widths=())
            if self.upright.sides and width is not None and not plan.holding(width) and width < plan.open_width - 0.01:
                # a box leaning with another side across the lean (the hand closes on its
                # 70 mm side at 73 mm): the same grip on that side
                plan = plan.shifted(width - plan.across)
            return plan
        return self.upright

    def standoff_poses(
        self,
        robot_xy: tuple[float, float],
        obj_xy: tuple[float, float],
        extra: float = 0.0,
        object_yaw: float | None = None,
        plan: GraspPlan | None = None,
    ) -> list[tuple[float, float, float]]:
        """Where the base may stop, facing the object (x, y, yaw), best first.

        Round objects: straight from the robot's side, then turning around the object in
        30 degree steps. Objects with ``sides`` and a known ``object_yaw``: those headings,
        the best side first and, within it, the one nearest the robot's side. ``plan``:
        the grasp (default the upright one), whose reach and sides count.
        """
        plan = plan or self.upright
        (rx, ry), (ox, oy) = robot_xy, obj_xy
        direct = math.atan2(oy - ry, ox - rx)
        d = plan.reach + self.approach.standoff + extra
        if plan.sides and object_yaw is not None:
            headings = []
            for rel in plan.sides:
                h = object_yaw + rel
                # the nearer of the two opposite faces first: it is on the robot's side
                pair = sorted((h, h + math.pi), key=lambda a: abs(_wrap(a - direct)))
                headings += [h + a for a in plan.offsets] if plan.one_way else pair
        else:
            headings = [direct + k * math.radians(30) for k in (0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6)]
        out, seen = [], set()
        for h in headings:
            h = _wrap(h)
            key = round(h, 6)
            if key not in seen:
                seen.add(key)
                out.append((ox - d * math.cos(h), oy - d * math.sin(h), h))
        return out

    def holding(self, closed_width: float) -> bool:
        """True when the fingers stopped at a width that means the object is held."""
        g = self.grasp
        assert g.closed_min is not None and g.closed_max is not None  # see upright
        return g.closed_min <= closed_width <= g.closed_max


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))
