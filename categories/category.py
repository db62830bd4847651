"""A category: everything about one kind of object, in one declaration.

The simulator builds its body from ``shape``, ``mass``, ``rgba`` and ``friction``;
perception recognises it by its colour (the hue of ``rgba``) and its measured shape; the
robot approaches and grasps it with ``approach`` and ``grasp``. See docs/categories.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from .shapes import Box, Label, Revolution, Shape
from .strategy import LYING_OFFSETS, Approach, Grasp, GraspPlan, Strategy, TopGrasp, derived_window

#: room the open fingers need around the held part [m]
FINGER_MARGIN = 0.01
#: half the height of a finger pad [m] (the OpenManipulator-X's pads are 30 mm tall)
PAD_HALF_HEIGHT = 0.015


@dataclass(frozen=True)
class Category:
    """One kind of object.

    Attributes:
        name: the category's name (``can``, ``carton``); what trees and ``eval`` ask for.
        shape: :class:`Revolution` (``Cylinder``) or :class:`Box`, standing upright [m].
        mass: [kg]. The arm lifts about 0.1 kg held at its reach.
        rgba: its colour (0..1); perception looks for this hue.
        grasp: how the gripper holds it (``Grasp.height`` above its base).
        approach: how the base comes to it.
        friction: the simulated body's lateral friction.
        description: one line for humans (``actorbt`` lists it).
        min_confidence: how sure perception must be to call a segment this category.
        label: a printed label around the body, or None (drawn in worlds with labels).
        top_grasp: how it is held from above when lying on its side (the defaults fit
            a can, a bottle or a carton).
    """

    name: str
    shape: Shape
    mass: float
    rgba: tuple[float, float, float, float]
    grasp: Grasp
    approach: Approach = field(default_factory=Approach)
    friction: float = 0.9
    description: str = ""
    min_confidence: float = 0.3
    label: Label | None = None
    top_grasp: TopGrasp = field(default_factory=TopGrasp)

    def __post_init__(self) -> None:
        if not self.name or not self.name.replace("_", "").isalnum():
            raise ValueError(f"a category name is letters, digits and _, got {self.name!r}")
        if not isinstance(self.shape, (Revolution, Box)):
            raise TypeError(f"{self.name}: shape must be a Revolution, Cylinder or Box, got {self.shape!r}")
        if self.mass <= 0:
            raise ValueError(f"{self.name}: mass must be positive, got {self.mass}")
        if len(self.rgba) not in (3, 4) or not all(0 <= c <= 1 for c in self.rgba):
            raise ValueError(f"{self.name}: rgba must be 3 or 4 numbers in 0..1, got {self.rgba}")
        if not self.sides():
            raise ValueError(
                f"{self.name}: no side of the {self.shape} fits the gripper's opening of "
                f"{self.grasp.open_width * 1000:.0f} mm"
            )
        if self.label is not None and self.label.top > self.shape.height:
            raise ValueError(f"{self.name}: the label ends above the object ({self.label.top} > {self.shape.height} m)")
        if not 0 < self.grasp.height < self.shape.height:
            raise ValueError(
                f"{self.name}: grasp height {self.grasp.height} m is not on the object (0..{self.shape.height} m)"
            )
        g = self.grasp
        if g.closed_min is None or g.closed_max is None:
            low, high = derived_window(self.held_width(), g.open_width)
            object.__setattr__(
                self,
                "grasp",
                replace(
                    g,
                    closed_min=low if g.closed_min is None else g.closed_min,
                    closed_max=high if g.closed_max is None else g.closed_max,
                ),
            )

    def held_width(self) -> float:
        """The width [m] the fingers close on, upright, at the grasp height: a body of
        revolution's widest section within the pads' height around it (a cone is held by
        its wider end), a box across its narrowest side that fits the hand."""
        if isinstance(self.shape, Revolution):
            h = self.grasp.height
            return 2 * max(
                self.shape.radius_at(z)
                for z in (h - PAD_HALF_HEIGHT, h, h + PAD_HALF_HEIGHT)
                if 0.0 <= z <= self.shape.height
            )
        return self.shape.width_across(self.sides()[0])

    @property
    def height(self) -> float:
        return self.shape.height

    @property
    def footprint_radius(self) -> float:
        return self.shape.footprint_radius

    def sides(self) -> tuple[float, ...]:
        """Headings [rad] relative to the object's yaw from which the open hand fits around
        it, narrowest grip first. A round object: ``(0.0,)`` (any heading)."""
        if isinstance(self.shape, Revolution):
            return (0.0,) if 2 * self.shape.body_radius <= self.grasp.open_width - FINGER_MARGIN else ()
        fits = [
            (self.shape.width_across(h), h)
            for h in (0.0, math.pi / 2)
            if self.shape.width_across(h) <= self.grasp.open_width - FINGER_MARGIN
        ]
        return tuple(h for _, h in sorted(fits))

    def lying_plans(self) -> tuple[GraspPlan, ...]:
        """How it is held lying on its side, from above, the fingers closing across it: a
        body of revolution across its body; a box across the face it shows from above,
        one plan per face it may lie on (``Box.rests``) that fits the hand."""
        t = self.top_grasp
        if isinstance(self.shape, Revolution):
            r = self.shape.body_radius
            # held at the middle of its body; a body with a neck is approached from its
            # base end, or the base, driving in, would push the longer end ahead of it
            faces = [(2 * r, r, len(self.shape.sections) > 1)]  # (width across, axis height, one way)
        else:
            faces = [(across, height / 2, False) for pose, (_, across), height in self.shape.rests() if pose == "lying"]
        return tuple(
            GraspPlan(
                reach=t.reach,
                height=mid + t.above_axis,
                pitch=math.pi / 2,
                open_width=self.grasp.open_width,
                closed_min=width - t.slack[0],
                closed_max=width + t.slack[1],
                lift=t.lift,
                sides=(0.0,),
                one_way=one_way,
                offsets=LYING_OFFSETS if one_way else (0.0,),
            )
            for width, mid, one_way in faces
            if width <= self.grasp.open_width - FINGER_MARGIN
        )

    @property
    def strategy(self) -> Strategy:
        sides = () if isinstance(self.shape, Revolution) else self.sides()
        size = (
            self.shape.height if isinstance(self.shape, Revolution) else max(self.shape.x, self.shape.y, self.shape.z)
        )
        return Strategy(
            self.name,
            self.approach,
            self.grasp,
            self.description,
            sides,
            self.lying_plans(),
            size,
            tuple(self.shape.width_across(h) for h in sides) if sides else (),
        )
