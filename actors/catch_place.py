"""Carrying and putting down: carry_pose, place and place_on, actors of Catcher
(actors/catch.py).
"""

from __future__ import annotations

import math
from dataclasses import replace

from bt_engine import ActorbtError, actor

from .catch_errors import ApproachError, GraspError
from .catch_geometry import BASE_MARGIN, BASE_OUTLINE, STANDOFF_CLEARANCE, surface_spots
from .catch_parts import CatcherParts
from .strategies import GraspPlan, strategy_for

#: place surface height and the part of the object held decide the release height
RELEASE_CLEARANCE = 0.008  # [m] above the surface when the fingers open
GENTLE_RELEASE = 0.006  # first opening step past the held width when letting go [m]
PLACE_INSET = 0.12  # how far inside a surface's edge the object is put down [m],
#                             at most: a hand of short reach (from above) puts it nearer
PLACE_SHORT = 0.04  # [m] a drive in to put an object down may stop this short
PLACE_ABOVE = 0.03  # the hand comes this far above where it lets go [m]
MIN_PLACE_REACH = 0.10  # [m] nearer the base, the object would be on it
PLACE_STANDOFF = 0.39  # the base stops at least this far from where it puts an
#                             object down before driving in [m]: room to turn (the
#                             upright grasp's standoff; a grasp from above reaches less)
STANDOFF_FARTHER = 0.30  # [m] how much farther back a standoff may move to find room:
#                             the nearest one is often a few cm short (a surface's edge on
#                             the map is rounded out to whole cells), the drive in makes up
STANDOFF_STEP = 0.02  # [m] the steps it moves back in


class Placing(CatcherParts):
    """Catcher's carry and place (a mixin of it: it uses Catcher's shared helpers and
    the approach's ``_free_standoff``)."""

    @actor(moves=True)
    def carry_pose(self) -> None:
        """Fold the arm with the object held, for driving."""
        self.run_actor("home")

    @actor(moves=True)
    def place(
        self, x: float, y: float, surface: float = 0.0, heading: float | None = None, standoff: float | None = None
    ) -> dict:
        """Put the held object down with its axis at (x, y) [m] on a surface ``surface`` [m]
        high, the base facing ``heading`` [rad] (default: from where it is).

        Args:
            x: where the object's axis goes, map frame x [m]
            y: where the object's axis goes, map frame y [m]
            surface: height of the surface it is put on [m]; 0: the floor
            heading: the base's heading while placing [rad]; None: facing (x, y) from
                the robot's side, or the nearest side with room for the base
            standoff: with ``heading``, how far back from (x, y) the base stops before
                it drives in [m]; None: the grasp's standoff (at least PLACE_STANDOFF)

        Returns:
            where the hand released it: x, y, z [m] in the map frame
        """
        held = self.get_value("holding")
        if not held:
            raise GraspError("place: nothing is held")
        strategy = strategy_for(held["category"])
        g, a = self.get_value("held_plan"), strategy.approach
        release_z = surface + g.height + RELEASE_CLEARANCE
        reach = self._place_reach(g, release_z)
        g = replace(g, reach=reach)
        if heading is None:
            rx, ry, _ = self.run_actor("get_pose")
            # the surface under the release point is on the map: no corridor check
            sx, sy, syaw = self._free_standoff((rx, ry), (x, y), strategy, corridor=False, plan=replace(g, sides=()))[0]
        else:
            d = standoff if standoff is not None else max(g.reach + a.standoff, PLACE_STANDOFF)
            sx, sy, syaw = x - d * math.cos(heading), y - d * math.sin(heading), heading
        self.run_actor("goto", sx, sy, syaw)
        self.run_actor("move_to_pose", g.reach, 0.0, release_z + PLACE_ABOVE, g.pitch)
        distance = self._face((x, y), strategy)
        start = self.run_actor("get_pose")
        try:
            driven = self._drive_in(distance - g.reach)
        except ActorbtError:
            # stopped short (the drive in can time out a centimetre or two before the
            # spot): a little short of it, the object still goes down on the surface
            here = self.run_actor("get_pose")
            driven = math.dist(start[:2], here[:2])
            if distance - g.reach - driven > PLACE_SHORT:
                raise
        self.run_actor("move_to_pose", g.reach, 0.0, release_z, g.pitch)
        # Let go gently: just past the object first, so the fingers' squeeze is released
        # without kicking it over, then wide enough to back out. Past it as the fingers
        # hold it now: an object that turned a little in them over the carry holds them
        # wider than after the pick, and opening to less would squeeze it again.
        self.run_actor("open", min(g.open_width, self._held_width(held) + GENTLE_RELEASE))
        self.run_actor("open", g.open_width)
        self.set_value("holding", None)
        self.set_value("held_plan", None)
        # Back the open hand out the way it came in: lifting or folding first could catch
        # an object that tilted in the fingers. A hand pointing down goes up first: the
        # fingers are around the object.
        # (as high as the arm reaches there: open fingers slide off along a lying body)
        if g.pitch > math.radians(45):
            up = release_z + g.lift
            while up > release_z + 0.01 and not self.run_actor("reachable", g.reach, 0.0, up, g.pitch):
                up -= 0.01
            self.run_actor("move_to_pose", g.reach, 0.0, up, g.pitch)
        self.run_actor("mini_walk", -max(0.1, driven))
        self.run_actor("home")
        return {"x": x, "y": y, "z": release_z}

    def _held_width(self, held: dict) -> float:
        """The fingers' opening on the held object now [m] (a grip check: they stall on
        it), or as the pick held it when they do not stall."""
        grip = self.run_actor("grip_check")
        return float(grip["width"]) if grip.get("stalled") else float(held["width"])

    def _place_reach(self, plan: GraspPlan, release_z: float) -> float:
        """How far ahead of the base the hand puts the object down [m]: the plan's reach,
        or nearer where the arm cannot hold it there above ``release_z`` (pointing down,
        it reaches less high the farther out)."""
        reach = plan.reach
        while not self.run_actor("reachable", reach, 0.0, release_z + PLACE_ABOVE, plan.pitch):
            reach -= 0.01
            if reach < MIN_PLACE_REACH:
                raise ApproachError(
                    f"the arm cannot put the object down {release_z:.2f} m high "
                    f"holding it as it does (tool pitch {math.degrees(plan.pitch):.0f} deg)"
                )
        return reach

    @actor(moves=True)
    def place_on(self, x: float, y: float, size_x: float, size_y: float, height: float, yaw: float = 0.0) -> dict:
        """Place the held object on a box-shaped surface (a pallet) centred at (x, y) [m],
        ``size_x`` by ``size_y`` [m] along its own axes, turned ``yaw`` [rad], ``height``
        [m] high: near the edge the robot can reach best, since the base cannot drive over
        the surface, and PLACE_SPACING away from the objects it put down before (a tidy-up
        brings several to one pallet: put on the same spot, one knocks the other off).

        Args:
            x: the surface's centre, map frame x [m]
            y: the surface's centre, map frame y [m]
            size_x: the surface's extent along its x axis [m]
            size_y: the surface's extent along its y axis [m]
            height: the surface's height above the floor [m]
            yaw: the surface's x axis from the map's [rad]

        Returns:
            where the hand released the object: x, y, z [m] in the map frame
        """
        held = self.get_value("holding")
        if not held:
            raise GraspError("place_on: nothing is held")
        plan = self.get_value("held_plan")
        standoff = max(plan.reach + strategy_for(held["category"]).approach.standoff, PLACE_STANDOFF)
        # the base's front stops short of the surface's edge
        reach = self._place_reach(plan, height + plan.height + RELEASE_CLEARANCE)
        inset = min(PLACE_INSET, reach - BASE_OUTLINE[1] - BASE_MARGIN)
        rx, ry, _ = self.run_actor("get_pose")
        taken = self.get_value("put_down")
        spots = surface_spots((x, y, size_x, size_y), inset, standoff, taken, (rx, ry), yaw)
        if not spots:
            raise ApproachError(
                f"the surface at ({x:.2f}, {y:.2f}) has no free spot left: {len(taken)} objects were put down on it"
            )
        failed = None
        room: dict[float, float] = {}  # each side's heading -> the most room found [m]
        for px, py, heading, _, _ in spots:
            d, clear = self._roomy_standoff((px, py), heading, standoff)
            side = round(heading, 3)
            room[side] = max(room.get(side, 0.0), clear)
            if d is None:
                continue
            try:
                released = self.run_actor("place", px, py, height, heading, d)
            except ActorbtError as e:
                if not self.get_value("holding"):
                    raise
                # still held: the next spot (a standoff free on the map can be blocked
                # for the navigation by what the robot sees there now)
                failed = e
                continue
            self.set_value("put_down", taken + [(px, py)])
            return released
        if failed is not None:
            raise failed
        sides = ", ".join(
            f"base facing {round(math.degrees(h)) % 360} deg: {c:.2f} m"
            for h, c in sorted(room.items(), key=lambda hc: math.degrees(hc[0]) % 360)
        )
        raise ApproachError(
            f"no side of the surface at ({x:.2f}, {y:.2f}) has room for the base: it needs "
            f"{STANDOFF_CLEARANCE:.2f} m clear of the map's obstacles {standoff:.2f}-"
            f"{standoff + STANDOFF_FARTHER:.2f} m back from a spot on the edge; the most "
            f"room on each side ({sides})"
        )

    def _roomy_standoff(self, spot: tuple[float, float], heading: float, nearest: float) -> tuple[float | None, float]:
        """The nearest standoff distance from ``spot`` [m], ``nearest`` or up to
        STANDOFF_FARTHER farther back along ``heading``, where the base has
        STANDOFF_CLEARANCE around it on the map (None if none), and the most clearance
        seen along the way [m]."""
        best = 0.0
        steps = int(round(STANDOFF_FARTHER / STANDOFF_STEP))
        for k in range(steps + 1):
            d = nearest + k * STANDOFF_STEP
            clear = float(self.run_actor("clearance", spot[0] - d * math.cos(heading), spot[1] - d * math.sin(heading)))
            best = max(best, clear)
            if clear >= STANDOFF_CLEARANCE:
                return d, best
        return None, best
